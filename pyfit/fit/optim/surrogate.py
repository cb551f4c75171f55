"""The NNO surrogate: a torch MLP from unit-scaled parameters to the residual vector.

Inputs are already in [0, 1]; outputs are standardised per component. Training: Adam on the mean
squared error, a validation split, early stopping on the validation loss (the best weights are kept).
"""
from __future__ import annotations

import numpy as np
import torch


class _one_thread:
    """Context: torch on one thread, restored afterwards. The network is tiny: a second thread only adds
    synchronisation to a population's forward pass, and the order of floating-point sums must not depend on
    the core count."""

    def __enter__(self):
        self.was = torch.get_num_threads()
        torch.set_num_threads(1)

    def __exit__(self, *exc):
        torch.set_num_threads(self.was)


class Surrogate:
    """MLP residual model; `predict` evaluates a whole population in one batched forward pass."""

    def __init__(self, hidden_sizes: list[int], seed: int = 0, validation_fraction: float = 0.2,
                 max_epochs: int = 3000, patience: int = 200, learning_rate: float = 1e-2):
        self.hidden_sizes = list(hidden_sizes)
        self.seed = seed
        self.validation_fraction = validation_fraction
        self.max_epochs = max_epochs
        self.patience = patience
        self.learning_rate = learning_rate
        self.net = None
        self.mean = self.scale = None
        self.validation_loss = float("nan")

    def _build(self, n_in, n_out):
        layers, width = [], n_in
        for h in self.hidden_sizes:
            layers += [torch.nn.Linear(width, h), torch.nn.Tanh()]
            width = h
        layers.append(torch.nn.Linear(width, n_out))
        return torch.nn.Sequential(*layers).double()

    def fit(self, X: np.ndarray, R: np.ndarray) -> "Surrogate":
        """Train on parameters X (n, d) in [0, 1] and residual vectors R (n, m).

        Deterministic: seeded and on one thread, so the order of floating-point sums does not depend on the
        core count; the CPU kernels it uses (linear layers, tanh, Adam) have no nondeterministic variant, so
        the same X, R and seed give the same network on any machine with the same torch build. (torch's
        use_deterministic_algorithms would add nothing on the CPU but the import of its compiler, seconds per
        process.)"""
        with _one_thread():
            return self._fit(X, R)

    def _fit(self, X: np.ndarray, R: np.ndarray) -> "Surrogate":
        torch.manual_seed(self.seed)
        rng = np.random.default_rng(self.seed)
        X = np.asarray(X, float)
        R = np.asarray(R, float)
        self.mean = R.mean(0)
        self.scale = R.std(0) + 1e-12
        Y = (R - self.mean) / self.scale
        n = len(X)
        n_val = int(round(self.validation_fraction * n)) if n >= 10 else 0
        order = rng.permutation(n)
        val, train = order[:n_val], order[n_val:]
        xt, yt = torch.from_numpy(X[train]), torch.from_numpy(Y[train])
        xv, yv = torch.from_numpy(X[val]), torch.from_numpy(Y[val])
        self.net = self._build(X.shape[1], R.shape[1])
        opt = torch.optim.Adam(self.net.parameters(), lr=self.learning_rate)
        best, best_state, since = np.inf, None, 0
        for _ in range(self.max_epochs):
            opt.zero_grad()
            loss = torch.mean((self.net(xt) - yt) ** 2)
            loss.backward()
            opt.step()
            with torch.no_grad():
                v = float(torch.mean((self.net(xv) - yv) ** 2)) if n_val else float(loss)
            if v < best - 1e-12:
                best, since = v, 0
                best_state = {k: t.clone() for k, t in self.net.state_dict().items()}
            else:
                since += 1
                if since > self.patience:
                    break
        self.net.load_state_dict(best_state)
        self.validation_loss = best
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Residual vectors (n, m) for parameters X (n, d)."""
        with torch.no_grad(), _one_thread():
            y = self.net(torch.from_numpy(np.atleast_2d(np.asarray(X, float)))).numpy()
        return y * self.scale + self.mean

    def predict_error(self, X: np.ndarray) -> np.ndarray:
        """Predicted scalar errors sum(r^2) for each row of X."""
        return np.sum(self.predict(X) ** 2, axis=1)
