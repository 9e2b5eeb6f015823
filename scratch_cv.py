"""Exploration sweep (not shipped): per-trial ARMSE for every candidate setting, cached."""
import json, math, sys, time, itertools
from pathlib import Path
import numpy as np
from indoorloc import pdr
from indoorloc.experiments import pdr_evaluate as pe
from indoorloc.io import list_pyshoe_trials, load_pyshoe_trial

ROOT = Path("/work/shared/data/pdr/pyshoe_vicon")
CACHE = Path("/tmp/wt16_cv"); CACHE.mkdir(exist_ok=True)
SA, SG = pe.SHOE_SIGMA_ACC_MPS2, pe.SHOE_SIGMA_GYRO_RADPS


def sliding_mean(x, w):
    # centred window of w samples, shifted inside at the ends (as the C++ SHOE)
    n = x.shape[0]
    c = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0)])
    k = np.arange(n)
    s = np.clip(k - w // 2, 0, n - w)
    return (c[s + w] - c[s]) / w


def stats(rec, w=5):
    t = np.asarray(pdr.shoe_statistic(rec.acc_mps2, rec.gyro_radps, window=w, sigma_acc_mps2=SA, sigma_gyro_radps=SG))
    are = sliding_mean(np.sum(rec.gyro_radps ** 2, 1), w) / SG ** 2
    a = rec.acc_mps2
    amv = (sliding_mean(np.sum(a ** 2, 1), w) - np.sum(sliding_mean(a, w) ** 2, 1)) / SA ** 2
    return {"shoe": np.log10(np.maximum(t, 1e-300)), "are": np.log10(np.maximum(are, 1e-300)),
            "amv": np.log10(np.maximum(amv, 1e-300))}


RECS = [load_pyshoe_trial(p) for p in list_pyshoe_trials(ROOT)]
STATS = [stats(r) for r in RECS]


def active_span(logt, hi=6.0):
    idx = np.flatnonzero(logt > hi)
    if idx.size == 0:
        return 0, logt.size
    return idx[0], idx[-1] + 1


# ---- candidate families: params -> stance
def fixed(st, p):
    return st["shoe"] < p["lg"]


def guard(st, p):
    # fixed threshold, raised until at least fmin of the active span is stance; optional cap
    x = st["shoe"]
    a, b = active_span(x) if p.get("active", True) else (0, x.size)
    q = np.quantile(x[a:b], p["fmin"])
    lg = max(p["lg"], q)
    if "cap" in p:
        lg = min(lg, p["cap"])
    return x < lg


def quant(st, p):
    x = st["shoe"]
    a, b = active_span(x)
    return x < np.quantile(x[a:b], p["q"])


def otsu_thr(x, bins=200):
    h, e = np.histogram(x, bins=bins)
    c = 0.5 * (e[1:] + e[:-1])
    w0 = np.cumsum(h); w1 = w0[-1] - w0
    m0 = np.cumsum(h * c) / np.maximum(w0, 1); m1 = (np.sum(h * c) - np.cumsum(h * c)) / np.maximum(w1, 1)
    between = w0 * w1 * (m0 - m1) ** 2
    return c[int(np.argmax(between))]


def otsu(st, p):
    x = st["shoe"]
    a, b = active_span(x)
    lg = otsu_thr(x[a:b]) + p["d"]
    q = np.quantile(x[a:b], p["fmin"])
    return x < max(lg, q)


def p99rule(st, p):
    x = st["shoe"]
    return x < (p["low"] if np.percentile(x, 99) < p["cut"] else p["high"])


def vote(st, p):
    x = st["shoe"]
    a, b = active_span(x)
    votes = np.zeros(x.size, int)
    for key in ("shoe", "are", "amv"):
        y = st[key]
        lg = max(p["lg_" + key], np.quantile(y[a:b], p["fmin"]))
        votes += y < lg
    return votes >= 2


FAMILIES = {
    "fixed": (fixed, [{"lg": v} for v in np.arange(4.0, 7.01, 0.25)]),
    "p99rule": (p99rule, [{"cut": c, "low": lo, "high": hi} for c in (7.2, 7.3, 7.4, 7.45, 7.5, 7.55)
                          for lo in (4.0, 4.5, 5.0) for hi in (5.3, 5.5, 5.7, 6.0)]),
    "guard": (guard, [{"lg": v, "fmin": f} for v in (4.0, 4.5, 5.0, 5.5, 6.0) for f in (0.0, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)]),
    "quant": (quant, [{"q": q} for q in np.arange(0.15, 0.61, 0.05)]),
    "otsu": (otsu, [{"d": d, "fmin": f} for d in (-2.0, -1.5, -1.0, -0.5, 0.0) for f in (0.0, 0.25, 0.35)]),
}


def key(name, p):
    return name + json.dumps({k: round(float(v), 4) for k, v in sorted(p.items())})


def run(name, smooth=True):
    fn, grid = FAMILIES[name]
    f = CACHE / f"{name}.json"
    res = json.loads(f.read_text()) if f.exists() else {}
    for p in grid:
        k = key(name, p)
        if k in res:
            continue
        rows = []
        for rec, st in zip(RECS, STATS):
            stance = fn(st, p)
            out = pdr.zupt_ekf(rec.time_s, rec.acc_mps2, rec.gyro_radps, stance, smooth=smooth)
            pos = np.asarray(out["positions_m"])
            r = pe.score_pyshoe_trial(rec, (pos, pe.strides_from_stance(stance, rec.rate_hz)))
            rows.append([r["armse_m"], r["stride_count_error"], float(stance.mean())])
        res[k] = {"p": {kk: float(v) for kk, v in p.items()}, "rows": rows}
        f.write_text(json.dumps(res))
    return res


def loo(res):
    keys = list(res)
    A = np.array([[r[0] for r in res[k]["rows"]] for k in keys])  # settings x trials
    S = np.array([[r[1] for r in res[k]["rows"]] for k in keys])
    n = A.shape[1]
    out, chosen = [], []
    for i in range(n):
        tr = [j for j in range(n) if j != i]
        best = int(np.argmin(A[:, tr].mean(1)))
        out.append((A[best, i], S[best, i])); chosen.append(keys[best])
    a = np.array([o[0] for o in out]); s = np.array([o[1] for o in out])
    truth = sum(r.stride_indices.size - 1 for r in RECS)
    return a, s, chosen, truth


if __name__ == "__main__":
    for name in sys.argv[1:]:
        t0 = time.time()
        res = run(name)
        a, s, chosen, truth = loo(res)
        from collections import Counter
        print(f"{name}: LOO median {np.median(a):.3f} mean {a.mean():.3f} worst {a.max():.3f} "
              f"(>0.4: {int((a > 0.4).sum())}) strides off {int(np.abs(s).sum())}/{truth}  [{time.time()-t0:.0f}s]")
        print("   chosen:", Counter(chosen).most_common(3))
        keys = list(res)
        A = np.array([[r[0] for r in res[k]["rows"]] for k in keys])
        b = int(np.argmin(A.mean(1)))
        print(f"   all-21 best {keys[b]}: mean {A[b].mean():.3f} worst {A[b].max():.3f}")
