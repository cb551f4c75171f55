"""Write a coupled system as an SSP 1.0 archive (System Structure and Parameterization, Modelica Association),
so that other tools can load it: SystemStructure.ssd (components, their connectors, parameter values,
connections, default experiment) plus the FMUs under resources/. fmpy reads and validates it against the
SSP schema and can simulate it."""
from __future__ import annotations

import pathlib
import zipfile
from xml.sax.saxutils import quoteattr

from fmpy import read_model_description

from pyfit.runtime.cosim import Connection

NS = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
      'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
      'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"')


def _component(name: str, fmu: pathlib.Path, used: set[str], params: dict) -> list[str]:
    md = read_model_description(str(fmu))
    lines = [f'      <ssd:Component name={quoteattr(name)} type="application/x-fmu-sharedlibrary" '
             f'source="resources/{fmu.name}">', "        <ssd:Connectors>"]
    for v in md.modelVariables:
        if v.causality in ("input", "output") and v.name in used:
            lines.append(f"          <ssd:Connector name={quoteattr(v.name)} kind=\"{v.causality}\"><ssc:Real/>"
                         "</ssd:Connector>")
    lines.append("        </ssd:Connectors>")
    if params:
        lines += ["        <ssd:ParameterBindings>", "          <ssd:ParameterBinding>",
                  "            <ssd:ParameterValues>",
                  f'              <ssv:ParameterSet version="1.0" name={quoteattr(name + "_parameters")}>',
                  "                <ssv:Parameters>"]
        for k, value in params.items():
            tag = "Integer" if isinstance(value, int) and not isinstance(value, bool) else "Real"
            lines.append(f"                  <ssv:Parameter name={quoteattr(k)}><ssv:{tag} value=\"{value!r}\"/>"
                         "</ssv:Parameter>")
        lines += ["                </ssv:Parameters>", "              </ssv:ParameterSet>",
                  "            </ssd:ParameterValues>", "          </ssd:ParameterBinding>",
                  "        </ssd:ParameterBindings>"]
    lines.append("      </ssd:Component>")
    return lines


def write_ssp(path: str | pathlib.Path, name: str, fmus: dict[str, str | pathlib.Path],
              connections: list[Connection], params: dict[str, dict] | None = None, stop_time: float = 1.0
              ) -> pathlib.Path:
    """Write `path` (.ssp): the FMUs (name -> file) coupled by `connections`, with parameter values."""
    path = pathlib.Path(path)
    fmus = {k: pathlib.Path(v) for k, v in fmus.items()}
    params = params or {}
    used: dict[str, set[str]] = {k: set() for k in fmus}
    for c in connections:
        for ref in (c.source, c.target):
            comp, _, var = ref.partition(".")
            if comp not in fmus:
                raise ValueError(f"connection end '{ref}': no FMU '{comp}'; FMUs: {', '.join(fmus)}")
            used[comp].add(var)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<ssd:SystemStructureDescription {NS} version="1.0" name={quoteattr(name)}>',
             f"  <ssd:System name={quoteattr(name)}>", "    <ssd:Elements>"]
    for comp, fmu in fmus.items():
        lines += _component(comp, fmu, used[comp], params.get(comp, {}))
    lines += ["    </ssd:Elements>", "    <ssd:Connections>"]
    for c in connections:
        (sc, _, sv), (tc, _, tv) = c.source.partition("."), c.target.partition(".")
        lines.append(f"      <ssd:Connection startElement={quoteattr(sc)} startConnector={quoteattr(sv)} "
                     f"endElement={quoteattr(tc)} endConnector={quoteattr(tv)}/>")
    lines += ["    </ssd:Connections>", "  </ssd:System>",
              f'  <ssd:DefaultExperiment startTime="0" stopTime="{stop_time!r}"/>',
              "</ssd:SystemStructureDescription>"]
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", "\n".join(lines) + "\n")
        for fmu in {f.resolve() for f in fmus.values()}:
            z.write(fmu, f"resources/{fmu.name}")
    return path
