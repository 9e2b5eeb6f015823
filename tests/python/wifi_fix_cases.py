"""Maps and scans shared by the fast-fix tests and their recorded reference (wifi fixes).

`partly_heard_case` is a survey where each AP is heard over part of the building only (its
mean and variance sit at the not-heard values elsewhere: the common real case the fast path
exploits); `dense_case` has no such structure (every entry distinct), the worst case.
"""

from __future__ import annotations

import numpy as np

NOT_HEARD_DBM = -105.0


def partly_heard_case(seed: int = 3, n_floors: int = 2, n_aps: int = 60, n_scans: int = 24):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 40, size=(150, 2))
    positions = np.vstack([xy] * n_floors)
    floors = np.repeat(np.arange(n_floors), len(xy))
    ap_xy = rng.uniform(0, 40, size=(n_aps, 2))
    ap_floor = rng.integers(0, n_floors, size=n_aps)

    def mean_at(p, f):
        d = np.sqrt(((p[:, None, :] - ap_xy[None]) ** 2).sum(axis=2) + 1.0)
        return -40.0 - 40.0 * np.log10(d) - 18.0 * np.abs(f[:, None] - ap_floor[None])

    mean = mean_at(positions, floors)
    heard = mean > -85.0
    mean = np.where(heard, mean, NOT_HEARD_DBM)
    var = np.where(heard, rng.uniform(3.0, 25.0, size=mean.shape), 4.0)
    q = rng.uniform(0, 40, size=(n_scans, 2))
    qf = rng.integers(0, n_floors, size=n_scans)
    v = mean_at(q, qf) + rng.normal(0, 4.0, size=(n_scans, n_aps))
    scans = np.where(v > -85.0, v, NOT_HEARD_DBM)
    return positions, floors, mean, var, scans


def dense_case(seed: int = 4, n_aps: int = 12, n_scans: int = 12):
    rng = np.random.default_rng(seed)
    positions = rng.uniform(0, 20, size=(80, 2))
    floors = np.zeros(80, dtype=int)
    mean = rng.uniform(-90, -40, size=(80, n_aps))
    var = rng.uniform(2.0, 30.0, size=(80, n_aps))
    scans = rng.uniform(-95, -35, size=(n_scans, n_aps))
    return positions, floors, mean, var, scans


CASES = {"partly_heard": partly_heard_case, "dense": dense_case}
# (variance floor [dB^2], max_term): the paper's model and a capped one.
MODELS = {"paper": (4.0, float("inf")), "capped": (9.0, 3.0)}


def fixes(wifi, case: str, model_name: str, method: str, group_size: int):
    """Positions, covariances, floors and neg_log_likelihood of one method on one case."""
    positions, floors, mean, var, scans = CASES[case]()
    floor_db2, cap = MODELS[model_name]
    model = wifi.RssModel(wifi.SignalMap(positions, floors, mean, var),
                          wifi.RssModelOptions(variance_floor_db2=floor_db2, max_term=cap))
    if method == "mmse":
        out = wifi.GridPosterior(model).locate(scans, group_size=group_size)
    else:
        out = wifi.locate_ml(model, scans, group_size=group_size)
    return {k: np.asarray(out[k], dtype=float) for k in ("positions_m", "covariances_m2", "floors", "neg_log_likelihood")}


def all_fixes(wifi) -> dict:
    arrays = {}
    for case in CASES:
        for model_name in MODELS:
            for method in ("mmse", "ml"):
                for group in (1, 3):
                    for key, value in fixes(wifi, case, model_name, method, group).items():
                        arrays[f"{case}/{model_name}/{method}/{group}/{key}"] = value
    return arrays


if __name__ == "__main__":  # records the reference from the build on PYTHONPATH
    import sys

    from indoorloc import wifi as _wifi

    np.savez_compressed(sys.argv[1], **all_fixes(_wifi))
