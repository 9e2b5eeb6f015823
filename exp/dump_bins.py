"""Binary inputs of exp/matcher_bench.cc and exp/fixer_bench.cc from the maps of dump_maps.py:
per floor N, K (int64), the map (N x K doubles, NaN = not heard), the AP weights g (K), 300
bench_fusion_live-style 200-AP queries and 300 noisy training fingerprints (300 x K each)."""
import pickle
import sys

import numpy as np

for name in sys.argv[1:]:
    db = pickle.load(open(f"/tmp/wifi_maps/{name}.pkl", "rb"))
    X = np.ascontiguousarray(db.rss_dbm, dtype=np.float64)
    g = np.asarray(db.index.g, np.float64)
    rng = np.random.default_rng(0)
    N, K = X.shape
    order = np.argsort(-np.isfinite(X).sum(0), kind="stable")[:200]
    Q = np.full((300, K), np.nan)
    for r in range(300):
        Q[r, order] = rng.uniform(-95, -40, len(order))
    R = X[rng.integers(0, N, 300)] + rng.normal(0, 4, (300, K))
    with open(f"/tmp/wifi_maps/{name}.bin", "wb") as f:
        np.array([N, K], np.int64).tofile(f)
        for a in (X, g, Q, R):
            a.tofile(f)
