"""Median / p99 time of matcher.nearest on bench_fusion_live's 200-reading queries and on real
pooled queries, per floor map dumped by dump_maps.py; also saves the results for bitwise checks."""
import sys, time, pickle, numpy as np
from pathlib import Path
maps = Path("/tmp/wifi_maps")
tag = next((a[4:] for a in sys.argv[1:] if a.startswith("tag=")), "cur")
for name in [a for a in sys.argv[1:] if not a.startswith("tag=")]:
    db = pickle.load(open(maps / f"{name}.pkl", "rb"))
    m = db.index.matcher(db.settings.penalty_db, db.settings.k, db.settings.temperature_db)
    rng = np.random.default_rng(0)
    heard = np.isfinite(db.rss_dbm).sum(axis=0)
    order = np.argsort(-heard, kind="stable")[:200]
    Q = np.full((300, len(db.bssids)), np.nan)
    for r in range(300):
        Q[r, order] = rng.uniform(-95, -40, len(order))
    # real-like queries: training fingerprints with noise
    R = db.rss_dbm[rng.integers(0, db.rss_dbm.shape[0], 300)] + rng.normal(0, 4, (300, len(db.bssids)))
    out = {}
    for label, qq in (("bench200", Q), ("realish", R)):
        ts = []
        res = []
        for r in range(qq.shape[0]):
            t0 = time.thread_time_ns(); nb = m.nearest(qq[r:r + 1], 1); ts.append(time.thread_time_ns() - t0)
            res.append(nb)
        ts = np.array(ts) / 1e3
        tb = time.perf_counter(); nbb = m.nearest(qq, 1); tb = time.perf_counter() - tb
        out[label] = nbb
        print(f"{name} {label}: single p50 {np.percentile(ts,50):.0f} p99 {np.percentile(ts,99):.0f} us; batch {1e6*tb/qq.shape[0]:.0f} us/query", flush=True)
    pickle.dump({k: tuple(v) for k, v in out.items()}, open(maps / f"{name}.nearest.{tag}.pkl", "wb"))
