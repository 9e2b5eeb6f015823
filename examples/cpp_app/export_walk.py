"""Python side of examples/cpp_app/site_app.cc (run by ``make test-cpp-app`` with the installed package).

    python export_walk.py survey DIR   # a synthetic survey folder DIR/survey (ILC 2020 layout) and a
                                       # walk held out of it, DIR/heldout.txt
    python export_walk.py walk DIR     # after 'indoorloc site build DIR/survey -o DIR/site.db': the
                                       # held-out walk's tracker inputs and the Python track, DIR/walk_events.txt

walk_events.txt (text, numbers with 17 significant digits), the held-out walk's raw sensor events
in time order (indoorloc.fusion.live.walk_events) and Python's causal track of it:
    floor NAME
    events E                then E lines, one event each:
                              acc T AX AY AZ | gyro T GX GY GZ | rv T N V1..VN | beacon T
                              wifi T N  followed by N lines: BSSID RSSI_DBM LAST_SEEN_S
    expected M              then M lines: t_s x_m y_m (the batch causal filter, live.causal_track,
                            on the site's models: the track a live replay must give)
"""

import shutil
import sys
from pathlib import Path

import numpy as np

from indoorloc.fusion import live
from indoorloc.fusion.site import Site
from indoorloc.io.ilc2020 import read_ilc_walk
from indoorloc.simulate.ilc_site import write_ilc_site


def survey(out: Path) -> None:
    if out.exists():
        shutil.rmtree(out)
    root = write_ilc_site(out / "survey", seed=0)
    walks = sorted((root / "F1" / "path_data_files").glob("*.txt"))
    shutil.move(str(walks[-1]), out / "heldout.txt")


def walk(out: Path) -> None:
    site = Site.open(out / "site.db")
    w = read_ilc_walk(out / "heldout.txt")
    m = site.floor_models("F1")
    track = live.causal_track(m.tracker, w, m.calibration, m.database,
                              step_length_sd_fraction=site.settings.step_length_sd_fraction,
                              step_heading_sd_rad=site.settings.step_heading_sd_rad)
    g = lambda v: f"{float(v):.17g}"  # noqa: E731
    events = list(live.walk_events(w, beacons=True))
    lines = ["floor F1", f"events {len(events)}"]
    short = {"accelerometer": "acc", "gyroscope": "gyro"}
    for kind, t, *values in events:
        if kind in short:
            lines.append(" ".join([short[kind], g(t)] + [g(v) for v in values[0][:3]]))
        elif kind == "rotation_vector":
            v = np.asarray(values[0], float).reshape(-1)
            lines.append(" ".join(["rv", g(t), str(v.size)] + [g(x) for x in v]))
        elif kind == "wifi":
            names, rssi, seen = values
            lines.append(f"wifi {g(t)} {len(names)}")
            lines += [f"{b} {g(r)} {g(s)}" for b, r, s in zip(names, rssi, seen)]
        else:
            lines.append(f"beacon {g(t)}")
    lines.append(f"expected {len(track['times_s'])}")
    lines += [f"{g(t)} {g(x)} {g(y)}" for t, (x, y) in zip(track["times_s"], track["mean_m"])]
    (out / "walk_events.txt").write_text("\n".join(lines) + "\n")
    print(f"export_walk: {len(events)} raw events of walk {w.walk_id}; Python's causal track: "
          f"{len(track['times_s'])} steps, {track['summary'].fixes} WiFi fixes")


if __name__ == "__main__":
    {"survey": survey, "walk": walk}[sys.argv[1]](Path(sys.argv[2]))
