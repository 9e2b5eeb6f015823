"""The linearised INS/GPS network (indoorloc._core.network.linear_ins_equations) in other solvers.

- :func:`sparse_normal_system`: whitened design matrix -> normal matrix A and right-hand side b
  (scipy.sparse), solved by :func:`solve_scipy` (SuperLU with COLAMD ordering, scipy's default
  sparse direct solver; scipy has no sparse Cholesky).
- :func:`solve_gtsam`: the same equations as a GTSAM GaussianFactorGraph of JacobianFactors
  (one per equation, noise models from the row sigmas), solved by ``graph.optimize()`` (GTSAM's
  default multifrontal elimination with COLAMD ordering), if gtsam is importable.

Unknown layout: 18 per epoch (δr, δv, ψ, accelerometer bias, gyro bias, δg), epoch n at
columns 18 n .. 18 n + 17. Peers of the benchmark only: never imported by the library.
"""

from __future__ import annotations

import time
from typing import Dict, Optional

import numpy as np

P = 18


def sparse_normal_system(eq: Dict[str, object]):
    """(A, b) of the network: A = Jᵀ W J (scipy CSC), b = Jᵀ W l."""
    import scipy.sparse as sp

    E = int(eq.imu_epochs)
    offsets = list(eq.offsets)
    J = [np.asarray(j) for j in eq.J]
    sigma = np.asarray(eq.row_sigma)
    centres = np.asarray(eq.centres, dtype=np.int64)
    l_dyn = np.asarray(eq.dynamic_l)
    rows, cols, vals, rhs = [], [], [], []
    n_eq = centres.size
    row_base = np.arange(n_eq, dtype=np.int64)[:, None] * P + np.arange(P)[None, :]  # (n_eq, 18)
    for a, off in enumerate(offsets):
        Ja = J[a] / sigma[:, None]
        nz_r, nz_c = np.nonzero(Ja)
        r = row_base[:, nz_r]
        c = (centres[:, None] + off) * P + nz_c[None, :]
        rows.append(r.ravel())
        cols.append(c.ravel())
        vals.append(np.broadcast_to(Ja[nz_r, nz_c], r.shape).ravel())
    rhs.append((l_dyn / sigma[None, :]).ravel())
    next_row = n_eq * P

    def add_static(epochs, values, first_col, width, s):
        nonlocal next_row
        epochs = np.asarray(epochs, dtype=np.int64)
        k = epochs.size
        if k == 0:
            return
        r = next_row + np.arange(k * width)
        c = (epochs[:, None] * P + first_col + np.arange(width)[None, :]).ravel()
        rows.append(r)
        cols.append(c)
        vals.append(np.full(k * width, 1.0 / s))
        rhs.append(np.asarray(values).ravel() / s)
        next_row += k * width

    add_static(eq.gps_epochs, eq.gps_l, 0, 3, eq.sigma_gps)
    prior_l = np.asarray(eq.prior_l)
    add_static(np.arange(prior_l.shape[0]), prior_l, 0, P, eq.sigma_prior)
    add_static(eq.gupt_epochs, eq.gupt_l, 15, 3, eq.sigma_gupt)
    Jw = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(next_row, E * P)
    )
    lw = np.concatenate(rhs)
    A = (Jw.T @ Jw).tocsc()
    b = Jw.T @ lw
    return A, b


def solve_scipy(eq: Dict[str, object]) -> Dict[str, object]:
    """Assemble with scipy.sparse and solve with SuperLU (COLAMD); timings in seconds."""
    from scipy.sparse.linalg import splu

    start = time.perf_counter()
    A, b = sparse_normal_system(eq)
    assemble = time.perf_counter() - start
    start = time.perf_counter()
    lu = splu(A, permc_spec="COLAMD")
    x = lu.solve(b)
    solve = time.perf_counter() - start
    return {"x": x, "assemble_seconds": assemble, "solve_seconds": solve,
            "factor_nnz": int(lu.L.nnz + lu.U.nnz)}


def gtsam_available() -> bool:
    try:
        import gtsam  # noqa: F401
    except ImportError:
        return False
    return True


def solve_gtsam(eq: Dict[str, object], qr: bool = False) -> Optional[Dict[str, object]]:
    """The network as a GTSAM linear factor graph, solved by graph.optimize() (default: multifrontal
    Cholesky, COLAMD ordering) or, with ``qr``, by multifrontal QR on the COLAMD ordering
    (gtsam.EliminateQR: slower, but it solves the long networks that the Cholesky declares
    indeterminate); None without gtsam."""
    if not gtsam_available():
        return None
    import gtsam

    start = time.perf_counter()
    graph = gtsam.GaussianFactorGraph()
    offsets = list(eq.offsets)
    J = [np.asarray(j) for j in eq.J]
    sigma = np.asarray(eq.row_sigma)
    dyn_noise = gtsam.noiseModel.Diagonal.Sigmas(sigma)
    centres = np.asarray(eq.centres, dtype=np.int64)
    l_dyn = np.asarray(eq.dynamic_l)
    for i, n in enumerate(centres):
        if len(offsets) == 3:
            graph.add(gtsam.JacobianFactor(int(n + offsets[0]), J[0], int(n + offsets[1]), J[1], int(n + offsets[2]), J[2],
                                           l_dyn[i], dyn_noise))
        else:
            graph.add(gtsam.JacobianFactor(int(n + offsets[0]), J[0], int(n + offsets[1]), J[1], l_dyn[i], dyn_noise))
    sel_r = np.zeros((3, P)); sel_r[:, 0:3] = np.eye(3)  # noqa: E702
    sel_g = np.zeros((3, P)); sel_g[:, 15:18] = np.eye(3)  # noqa: E702
    gps_noise = gtsam.noiseModel.Isotropic.Sigma(3, float(eq.sigma_gps))
    for n, l in zip(eq.gps_epochs, np.asarray(eq.gps_l)):
        graph.add(gtsam.JacobianFactor(int(n), sel_r, l, gps_noise))
    prior_noise = gtsam.noiseModel.Isotropic.Sigma(P, float(eq.sigma_prior))
    for n, l in enumerate(np.asarray(eq.prior_l)):
        graph.add(gtsam.JacobianFactor(int(n), np.eye(P), l, prior_noise))
    gupt_noise = gtsam.noiseModel.Isotropic.Sigma(3, float(eq.sigma_gupt))
    for n, l in zip(eq.gupt_epochs, np.asarray(eq.gupt_l)):
        graph.add(gtsam.JacobianFactor(int(n), sel_g, l, gupt_noise))
    assemble = time.perf_counter() - start
    start = time.perf_counter()
    if qr:
        values = graph.eliminateMultifrontal(gtsam.Ordering.ColamdGaussianFactorGraph(graph), gtsam.EliminateQR).optimize()
    else:
        values = graph.optimize()
    solve = time.perf_counter() - start
    E = int(eq.imu_epochs)
    x = np.concatenate([values.at(n) for n in range(E)])
    return {"x": x, "assemble_seconds": assemble, "solve_seconds": solve}
