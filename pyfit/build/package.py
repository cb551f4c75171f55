"""Compile the generated C sources with gcc and zip them into an FMU."""
from __future__ import annotations

import os
import pathlib
import platform
import shutil
import subprocess
import sys
import tempfile
import zipfile

import fmpy

WRAPPER = pathlib.Path(__file__).with_name("fmi2_wrapper.c")
FMI2_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")


def platform_folder() -> str:
    """FMI 2.0 binaries folder name of this machine (linux64, darwin64, win64)."""
    system = {"Linux": "linux", "Darwin": "darwin", "Windows": "win"}[platform.system()]
    return system + ("64" if sys.maxsize > 2**32 else "32")


def compile_and_zip(ident: str, src_dir: pathlib.Path, description_xml: bytes, fmu_path: pathlib.Path,
                    extra_files: dict[str, bytes] | None = None, cc: str | None = None) -> pathlib.Path:
    """Compile `src_dir` into binaries/<platform>/<ident>.so and write the .fmu (atomically)."""
    header_dir = pathlib.Path(fmpy.__file__).parent / "c-code"
    shutil.copy(WRAPPER, src_dir / WRAPPER.name)
    for h in FMI2_HEADERS:
        shutil.copy(header_dir / h, src_dir / h)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        suffix = {"linux": ".so", "darwin": ".dylib", "win": ".dll"}[platform_folder()[:-2]]
        lib = tmp / (ident + suffix)
        cmd = [cc or os.environ.get("CC", "gcc"), "-shared", "-fPIC", "-O2", "-std=c99", "-I", str(src_dir),
               str(src_dir / "model_functions.c"), str(src_dir / WRAPPER.name), "-o", str(lib), "-lm"]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"C compilation of {ident} failed:\n{' '.join(cmd)}\n{proc.stderr[-4000:]}")
        fmu_path.parent.mkdir(parents=True, exist_ok=True)
        partial = fmu_path.with_suffix(".fmu.partial")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", description_xml)
            z.write(lib, f"binaries/{platform_folder()}/{lib.name}")
            for f in sorted(src_dir.iterdir()):
                z.write(f, f"sources/{f.name}")
            for name, data in (extra_files or {}).items():
                z.writestr(name, data)
        partial.replace(fmu_path)
    return fmu_path
