"""The track viewer on real walks: the shared ILC 2020 site (floors F8 and F1), each walk tracked as
a test walk of its own fold (the models from the other walks of its floor, as
``indoorloc fusion evaluate`` does), written to one page; then a screenshot of the page in
headless Chromium with the slider moved to mid-walk (docs/images/viewer_example.png).

    python examples/track_viewer/make_example.py [--out DIR] [--data ROOT] [--no-screenshot]

Needs the shared data (/work/shared/data/fusion/ilc2020_site2 or --data) and, for the
screenshot, Debian's chromium + chromium-driver and selenium (the test extra).
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from indoorloc.experiments import fusion_real as fr
from indoorloc.fusion.viewer import ViewerTrack, viewer_floor_from_plan, write_viewer_html

#: (floor, walk index): the longest walks of F8 and one of F1.
WALKS = (("F8", 5), ("F8", 12), ("F1", 3))


def viewer_track(snapshot: dict, label: str) -> ViewerTrack:
    """A ViewerTrack from :func:`indoorloc.experiments.fusion_real.walk_snapshot`'s dict: the
    smoothed track with its smoothed covariances, the surveyed waypoints and the WiFi fixes."""
    cov = snapshot["smoothed_covariance_m2"]
    sd = rho = None
    if cov is not None:
        sd = np.sqrt(np.c_[cov[:, 0], cov[:, 2]])
        rho = np.clip(cov[:, 1] / np.maximum(sd[:, 0] * sd[:, 1], 1e-12), -1.0, 1.0)
    return ViewerTrack(label, snapshot["floor"], snapshot["track_t_s"], snapshot["smoothed_m"], sd_m=sd,
                       xy_correlation=rho, waypoints_t_s=snapshot["waypoint_t_s"],
                       waypoints_xy_m=snapshot["waypoints_m"], fixes_t_s=snapshot["fix_t_s"],
                       fixes_xy_m=snapshot["fix_centres_m"])


def screenshot(page: Path, png: Path, slider_fraction: float = 0.6) -> None:
    """Open the page in headless Chromium (Debian's driver, never a downloaded one), click the
    slider at ``slider_fraction`` of its length and save a screenshot."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,1050", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(executable_path="/usr/bin/chromedriver"), options=options)
    try:
        driver.set_page_load_timeout(30)
        driver.get(page.resolve().as_uri())
        time.sleep(1.0)
        rail = [e for e in driver.find_elements(By.CSS_SELECTOR, ".slider-rail-touch-rect") if e.size["width"] > 0][0]
        offset = int(rail.size["width"] * (slider_fraction - 0.5))  # from the rail's centre
        ActionChains(driver).move_to_element_with_offset(rail, offset, 0).click().perform()
        time.sleep(0.5)
        driver.save_screenshot(str(png))
    finally:
        driver.quit()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("docs/images"))
    ap.add_argument("--data", type=Path, default=None, help="ILC 2020 site folder (default: the shared data)")
    ap.add_argument("--no-screenshot", action="store_true")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    # The loader's notes on damaged beacon fields no method here needs (docs/errors.md).
    warnings.filterwarnings("ignore", message=".*damaged data that no method needs.*")
    tic = time.perf_counter()
    floors, tracks = {}, []
    for floor, index in WALKS:
        snap = fr.walk_snapshot(args.data, floor, index)
        if floor not in floors:
            _, (fl,) = fr.load_site(args.data, [floor])
            floors[floor] = viewer_floor_from_plan(fl.plan, 0, name=floor)
        err = snap["errors"]["fusion_smoother"]
        tracks.append(viewer_track(snap, f"{floor} walk {index}"))
        print(f"{floor} walk {index} ({snap['walk']}): {len(snap['track_t_s'])} steps, "
              f"smoother error at the waypoints mean {np.mean(err):.1f} m")
    page = write_viewer_html(args.out / "viewer_example.html", list(floors.values()), tracks,
                             title="indoorloc track viewer: ILC 2020 site 2")
    print(f"wrote {page} ({page.stat().st_size / 1e6:.1f} MB) in {time.perf_counter() - tic:.1f} s")
    if not args.no_screenshot:
        png = args.out / "viewer_example.png"
        screenshot(page, png)
        print(f"wrote {png}")


if __name__ == "__main__":
    main()
