"""Time (and perf-profile) bench_fusion_live's 200-reading scans on a LiveTracker with a dumped map."""
import sys, time, pickle, gc, numpy as np
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import bench_fusion_live as b
from indoorloc import fusion
from indoorloc.fusion import live
from indoorloc.pdr import handheld as ph
from indoorloc.io import load_floor_plan, read_ilc_floor
name = sys.argv[1]; n = int(sys.argv[2]) if len(sys.argv) > 2 else 400
db = pickle.load(open(f"/tmp/wifi_maps/{name}.pkl", "rb"))
floor = read_ilc_floor(b.SHARED / name)
walk = max(floor.walks(), key=lambda w: w.duration_s)
cal = ph.calibrate_handheld([walk])
plan = load_floor_plan(floor.geojson_path, floors=[b._floor_number(name)], origin_lon_lat="outline_sw")
tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions())
lt = live.LiveTracker(tracker, cal, db)
rng = np.random.default_rng(0)
cpu = []
base = [b._scan_200(db, rng, 0.0) for k in range(50)]
scans = [(nm, r, sn + 1000.0 + k) for k in range(n) for nm, r, sn in [base[k % 50]]]
gc.disable()
for k, (names, rssi, seen) in enumerate(scans):
    c0 = time.thread_time_ns()
    lt.add_wifi_scan(1000.0 + k, names, rssi, seen)
    cpu.append(time.thread_time_ns() - c0)
a = np.array(cpu[20:]) / 1e3
print(f"{name}: scan_200 cpu p50 {np.percentile(a,50):.0f} p99 {np.percentile(a,99):.0f} max {a.max():.0f} us")
