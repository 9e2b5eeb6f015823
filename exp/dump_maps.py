"""Dump per-floor fingerprint maps (bench_fusion_live's: every walk but the longest) to npz, for
latency profiling of the matcher outside Python."""
import sys, numpy as np, pickle
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import bench_fusion_live as b
from indoorloc.pdr import handheld as ph
from indoorloc.fusion import wifi_fixes as wfx
from indoorloc.io import read_ilc_floor
out = Path("/tmp/wifi_maps"); out.mkdir(exist_ok=True)
for name in sys.argv[1:]:
    floor = read_ilc_floor(b.SHARED / name)
    walks = list(floor.walks())
    ti = int(np.argmax([w.duration_s for w in walks]))
    train = [w for i, w in enumerate(walks) if i != ti]
    db = wfx.build_database(train, wfx.FixSettings(), [ph.handheld_steps(w) for w in train], floors=[b._floor_number(name)] * len(train))
    with open(out / f"{name}.pkl", "wb") as f:
        pickle.dump(db, f)
    heard = np.isfinite(db.rss_dbm)
    print(name, db.rss_dbm.shape, heard.sum(), heard.sum(1).mean(), np.sort(heard.sum(0))[::-1][:200].sum(), flush=True)
