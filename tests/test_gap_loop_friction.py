"""Sim-to-real gap diagnosis on the withheld-hysteresis and withheld-Coulomb-friction SDOF datasets (CI
budgets; the other two effects: test_gap.py, a file of their own so that the test workers share the four
diagnoses): the withheld effect ranked first where it acts, the friction force recovered."""
import pytest

from gap_cases import found_where_it_acts, strength_recovered


@pytest.fixture(scope="module")
def data_root(tmp_path_factory):
    return tmp_path_factory.mktemp("gap_loop_friction")


@pytest.mark.parametrize("effect", ["hysteresis", "coulomb_friction"])
def test_withheld_effect_is_found_where_it_acts_and_removes_the_gap(data_root, fmu_dir, effect, measured):
    found_where_it_acts(data_root, fmu_dir, effect, measured)


def test_chosen_effect_recovers_the_withheld_friction_force(data_root, fmu_dir, measured):
    strength_recovered(data_root, fmu_dir, "coulomb_friction", "F_c", measured)
