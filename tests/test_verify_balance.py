"""The energy balance against a time-domain co-simulation of the same span in wind: ConductorSpan with the
CIGRE wind on one mode, DamperElement at its clamp."""
import pytest

from pyfit.design.verification import check_mode


# mode 12 (26.2 Hz) in the default run; 5 (10.9 Hz) and 22 (48.1 Hz) with `python -m pytest -m slow`
@pytest.mark.parametrize("mode", [pytest.param(5, marks=pytest.mark.slow), 12, pytest.param(22, marks=pytest.mark.slow)])
def test_energy_balance_agrees_with_the_span_cosimulated_in_wind(mode, runner, measured):
    """30 m Drake span (ConductorSpan FMU, 27 modes, viscous ζ = 0.002) with the CIGRE wind on one mode as an
    amplitude-dependent negative damping, the DamperElement FMU at 1 m from the end, co-simulated for 12 s
    from 0.8 × the balance's amplitude: the steady antinode amplitude of the mode against the energy balance
    (with the damper's reaction) at the same frequency."""
    check = check_mode(runner("ConductorSpan"), runner("DamperElement"), mode, 1.0, duration=12.0)
    assert check.settled < 2e-3
    measured(f"energy balance vs co-simulation in wind, span mode {mode} ({check.frequency_hz:.1f} Hz), damper at "
             "1 m: |relative difference| of the steady antinode amplitude", abs(check.relative_difference), 0.05)
