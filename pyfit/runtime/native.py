"""The compiled co-simulation master loop (cs_driver.c): built once per machine, loaded with ctypes.

The library is compiled with the C compiler the FMU build uses (``$CC``, default gcc) into
``$PYFIT_CACHE`` (default ``~/.cache/pyfit``), named by the hash of its source, so a changed source is
rebuilt and parallel workers never see a half-written file. Without a compiler, ``cs_loop()`` returns
None and FmuRunner runs the same loop in Python (slower, same results).
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import pathlib
import subprocess
import tempfile
import warnings

SOURCE = pathlib.Path(__file__).with_name("cs_driver.c")
_loaded: dict[str, object] = {}


def cache_dir() -> pathlib.Path:
    """Folder for compiled helpers: $PYFIT_CACHE, else ~/.cache/pyfit."""
    return pathlib.Path(os.environ.get("PYFIT_CACHE", pathlib.Path.home() / ".cache" / "pyfit"))


def _compile(lib: pathlib.Path) -> None:
    lib.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=lib.parent, suffix=".so.partial", delete=False) as tmp:
        partial = pathlib.Path(tmp.name)
    cmd = [os.environ.get("CC", "gcc"), "-shared", "-fPIC", "-O2", "-std=c99", str(SOURCE), "-o", str(partial)]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise OSError(f"{' '.join(cmd)}: {proc.stderr[-2000:]}")
        partial.replace(lib)
    finally:
        partial.unlink(missing_ok=True)


def cs_loop():
    """The compiled `pyfit_cs_run` function, or None (with one warning) when it cannot be built."""
    if "fn" not in _loaded:
        digest = hashlib.sha256(SOURCE.read_bytes()).hexdigest()[:16]
        lib = cache_dir() / f"cs_driver-{digest}.so"
        try:
            if not lib.is_file():
                _compile(lib)
            fn = ctypes.CDLL(str(lib)).pyfit_cs_run
        except OSError as exc:
            warnings.warn(f"compiled co-simulation loop unavailable, using the Python loop: {exc}")
            fn = None
        else:
            p, i = ctypes.c_void_p, ctypes.c_int
            fn.argtypes = [p, p, p, p, p, i, p, i, p, p, p, p, i, p, p, ctypes.POINTER(i), ctypes.POINTER(i),
                           ctypes.c_double]
            fn.restype = i
        _loaded["fn"] = fn
    return _loaded["fn"]
