"""Real external data: the SDOF FMU against the official Bouc-Wen benchmark validation outputs."""
import os

import pytest

from pyfit.io import benchmark_data as bd

if not bd.DEFAULT_DIR.is_dir():
    if os.environ.get("CI"):  # CI has ../shared beside the clone: a missing folder there is an error
        raise FileNotFoundError(f"benchmark data not found at {bd.DEFAULT_DIR}")
    pytest.skip(f"benchmark data not found at {bd.DEFAULT_DIR} (../shared/data/boucwen or BOUCWEN_DATA_DIR)",
                allow_module_level=True)


def test_multisine_matches_official_output_to_minus_125_db(runner, measured):
    sig = bd.load("multisine")
    y = bd.simulate_validation(runner("SDOFBoucWen"), sig, upsample=20, periods=3)
    db = bd.rms_db(y - sig.y)
    # exact-model floor is about -132 dB (design section 8); a wrong sign or parameter gives > -60 dB
    measured("SDOF FMU on the official benchmark multisine (band-limited upsampling to 15 kHz, 3 periods, last "
             "compared): RMS error [dB re 1 m]", db, -125.0)


def test_sinesweep_matches_official_output_to_minus_108_db(runner, measured):
    sig = bd.load("sinesweep")
    y = bd.simulate_validation(runner("SDOFBoucWen"), sig, upsample=4)
    db = bd.rms_db(y - sig.y)
    # floor -111.8 dB: the benchmark's own integration error grows linearly along the sweep
    measured("SDOF FMU on the official benchmark sine sweep (spline upsampling ×4, from rest): RMS error [dB re 1 m]",
             db, -108.0)
