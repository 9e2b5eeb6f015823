"""Python side of examples/cpp_app/site_app.cc (run by ``make test-cpp-app`` with the installed package).

    python export_walk.py survey DIR   # a synthetic survey folder DIR/survey (ILC 2020 layout) and a
                                       # walk held out of it, DIR/heldout.txt
    python export_walk.py walk DIR     # after 'indoorloc site build DIR/survey -o DIR/site.db': the
                                       # held-out walk's tracker inputs and the Python track, DIR/walk_events.txt

walk_events.txt (text, numbers with 17 significant digits):
    floor NAME
    steps M                 then M lines: t_s dx_m dy_m cov_xx cov_xy cov_yy
    fixes F                 then per fix: "t_s K" and K lines: x_m y_m sd_m weight floor
    expected M              then M lines: x_m y_m (Python's smoothed track from the same site file)
"""

import shutil
import sys
from pathlib import Path

import numpy as np

from indoorloc.pdr import handheld as ph
from indoorloc.fusion import wifi_fixes
from indoorloc.fusion import site_model
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
    track = site.track(w, floor="F1")
    m = site.floor_models("F1")
    steps = site_model.tracker_steps(ph.handheld_steps(w), m.calibration, site.settings)
    fixes = wifi_fixes.fixes_for_walk(w, m.database)
    g = lambda v: f"{float(v):.17g}"  # noqa: E731
    lines = ["floor F1", f"steps {len(steps)}"]
    cov = np.asarray(steps.covariances_m2).reshape(len(steps), -1)
    for t, d, c in zip(steps.times_s, steps.displacements_m, cov):
        c3 = (c[0], c[1], c[3]) if c.size == 4 else tuple(c)
        lines.append(" ".join(g(v) for v in (t, d[0], d[1], *c3)))
    lines.append(f"fixes {len(fixes)}")
    for i in range(len(fixes)):
        keep = np.flatnonzero(fixes.weights[i] > 0)
        lines.append(f"{g(fixes.times_s[i])} {keep.size}")
        for k in keep:
            lines.append(" ".join([g(fixes.means_m[i, k, 0]), g(fixes.means_m[i, k, 1]), g(fixes.sds_m[i, k]),
                                   g(fixes.weights[i, k]), str(int(fixes.floors[i, k]))]))
    lines.append(f"expected {track.xy_m.shape[0]}")
    lines += [f"{g(x)} {g(y)}" for x, y in track.xy_m]
    (out / "walk_events.txt").write_text("\n".join(lines) + "\n")
    print(f"export_walk: {len(steps)} steps, {len(fixes)} fixes of walk {w.walk_id}; Python track error "
          f"mean {np.mean(track.errors_m):.2f} m")


if __name__ == "__main__":
    {"survey": survey, "walk": walk}[sys.argv[1]](Path(sys.argv[2]))
