"""Shared by the SDOF gap-diagnosis test files: the withheld-effect datasets and the CI budgets."""
from pyfit.gap import datasets
from pyfit.gap import diagnose as dg

# CI budgets: fewer evaluations per fit, and the forward selection from the best single effect only with three
# partners (the default search, two starts and every partner, runs in the slow tier and the campaign)
CI = dg.DiagnoseConfig(nominal_budget=30, refit_budget=60, beam=1, partners=3)


def case(root, effect, seed=0):
    """The dataset of that withheld effect ('none': a null case), written once per test module."""
    path = root / f"{effect}_seed{seed}"
    if not path.is_dir():
        datasets.write_dataset(path, datasets.SDOF, effect, seed=seed, periods=2)
    return path
