"""Shared by the SDOF gap-diagnosis test files: the withheld-effect datasets and the CI budgets."""
from pyfit.gap import datasets
from pyfit.gap import diagnose as dg

CI = dg.DiagnoseConfig(nominal_budget=30, refit_budget=60)


def case(root, effect, seed=0):
    """The dataset of that withheld effect ('none': a null case), written once per test module."""
    path = root / f"{effect}_seed{seed}"
    if not path.is_dir():
        datasets.write_dataset(path, datasets.SDOF, effect, seed=seed, periods=2)
    return path
