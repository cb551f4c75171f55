"""Compile the generated C sources with gcc and zip them into FMUs (FMI 2.0, and FMI 3.0 from the same objects)."""
from __future__ import annotations

import os
import pathlib
import platform
import shutil
import subprocess
import sys
import tempfile
import threading
import zipfile

import fmpy

HERE = pathlib.Path(__file__).parent
FMI2_WRAPPER = HERE / "fmi2_wrapper.c"
FMI3_ADAPTER = HERE / "fmi3_adapter.c"
HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h",
           "fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")
LIB_SUFFIX = {"Linux": ".so", "Darwin": ".dylib", "Windows": ".dll"}


def platform_folder(fmi_version: str = "2.0") -> str:
    """Binaries folder name of this machine: FMI 2.0 'linux64' etc., FMI 3.0 'x86_64-linux' etc."""
    system = platform.system()
    if fmi_version == "2.0":
        return {"Linux": "linux", "Darwin": "darwin", "Windows": "win"}[system] + (
            "64" if sys.maxsize > 2**32 else "32")
    arch = {"amd64": "x86_64", "arm64": "aarch64"}.get(platform.machine().lower(), platform.machine().lower())
    return f"{arch}-{system.lower()}"


def _run(cmd: list[str], ident: str) -> None:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"C compilation of {ident} failed:\n{' '.join(cmd)}\n{proc.stderr[-4000:]}")


def _zip(fmu_path: pathlib.Path, documents: dict[str, bytes], lib: pathlib.Path, binaries: str,
         sources: list[pathlib.Path]) -> None:
    fmu_path.parent.mkdir(parents=True, exist_ok=True)
    # a name of this process's own: two processes building the same FMU at once (two workers that both found it
    # older than its sources) must not move each other's file away
    partial = fmu_path.with_suffix(f".fmu.{os.getpid()}.{threading.get_ident()}.partial")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in documents.items():
            z.writestr(name, data)
        z.write(lib, f"binaries/{binaries}/{lib.name}")
        for f in sources:
            z.write(f, f"sources/{f.name}")
    partial.replace(fmu_path)  # atomic: a reader never sees a partial FMU


def compile_and_zip(ident: str, src_dir: pathlib.Path, documents: dict[str, dict[str, bytes]],
                    fmu_paths: dict[str, pathlib.Path], cc: str | None = None) -> dict[str, pathlib.Path]:
    """Compile `src_dir` once and write one .fmu per FMI version in `documents` ('2.0', '3.0'; each maps archive
    names such as modelDescription.xml to their contents): the FMI 3.0 library is the FMI 2.0 one plus
    fmi3_adapter.c. Each FMU's sources/ holds what its library is built from."""
    header_dir = pathlib.Path(fmpy.__file__).parent / "c-code"
    for f in (FMI2_WRAPPER, FMI3_ADAPTER):
        shutil.copy(f, src_dir / f.name)
    for h in HEADERS:
        shutil.copy(header_dir / h, src_dir / h)
    cc = cc or os.environ.get("CC", "gcc")
    flags = ["-fPIC", "-O3", "-std=c99", "-I", str(src_dir)]
    units = {"model": "model_functions.c", "fmi2": FMI2_WRAPPER.name, "fmi3": FMI3_ADAPTER.name}
    sources = {"2.0": ["model", "fmi2"], "3.0": ["model", "fmi2", "fmi3"]}
    headers = sorted(p for p in src_dir.iterdir() if p.suffix == ".h")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        needed = sorted({u for v in documents for u in sources[v]})
        for u in needed:
            _run([cc, *flags, "-c", str(src_dir / units[u]), "-o", str(tmp / f"{u}.o")], ident)
        written = {}
        for version, docs in documents.items():
            lib = tmp / version / (ident + LIB_SUFFIX[platform.system()])
            lib.parent.mkdir()
            _run([cc, "-shared", *[str(tmp / f"{u}.o") for u in sources[version]], "-o", str(lib), "-lm"], ident)
            files = [src_dir / units[u] for u in sources[version]] + [
                h for h in headers if version == "3.0" or not h.name.startswith("fmi3")]
            _zip(fmu_paths[version], docs, lib, platform_folder(version), files)
            written[version] = fmu_paths[version]
    return written
