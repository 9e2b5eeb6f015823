"""The track viewer (indoorloc.fusion.viewer): page content and input checks without a browser,
then the page in a real headless Chromium (Debian's chromium + chromedriver, driven by selenium):
it loads without console errors and without any request leaving the page, the time slider moves
the marker, the walk selector switches walk and floor, and a screenshot is taken.

The browser part skips (with the reason) only where chromium is absent and CI is not "true";
`make test` installs chromium, so under CI a missing browser is a failure."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from indoorloc import fusion
from indoorloc.fusion.viewer import (ViewerFloor, ViewerTrack, decimate, viewer_floor_from_plan,
                                     write_viewer_html)

pytest.importorskip("plotly", reason="the viewer needs plotly (the package's dependency)")

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"


def _floors():
    outline = np.array([[0, 0], [40, 0], [40, 20], [0, 20]], float)
    shops = [np.array([[5, 5], [15, 5], [15, 15], [5, 15]], float),
             np.array([[25, 5], [35, 5], [35, 12], [25, 12]], float)]
    square = np.array([[0, 0], [30, 0], [30, 30], [0, 30]], float)
    return [ViewerFloor("F1", [outline], shops), ViewerFloor("F2", [square], [])]


def _tracks(n=600):
    t = np.linspace(0.0, 120.0, n)
    xy = np.c_[20 + 17 * np.cos(t / 20), 10 + 8 * np.sin(t / 20)]
    sd = np.c_[1 + 0.5 * np.sin(t / 7) ** 2, 0.8 + 0.3 * np.cos(t / 5) ** 2]
    a = ViewerTrack("walk A", "F1", t + 1000.0, xy, sd_m=sd, waypoints_t_s=t[::60] + 1000.0,
                    waypoints_xy_m=xy[::60] + 0.5, fixes_t_s=t[::30] + 1000.0, fixes_xy_m=xy[::30] - 0.7,
                    floor_probability=np.linspace(0.5, 1.0, n), xy_correlation=0.4 * np.sin(t / 10))
    b = ViewerTrack("walk B", "F2", t, np.c_[15 + 10 * np.cos(t / 30), 15 + 10 * np.sin(t / 30)])
    return [a, b]


def _figure_json(html: str) -> dict:
    """The figure's data and layout as the page holds them (plotly's Plotly.newPlot call)."""
    m = re.search(r'Plotly\.newPlot\(\s*"indoorloc-viewer",\s*(\[.*?\]),\s*(\{.*?\}),\s*\{"displaylogo"', html, re.S)
    assert m, "the page has no Plotly.newPlot call for the viewer div"
    return {"data": json.loads(m.group(1)), "layout": json.loads(m.group(2))}


# ---- without a browser ---------------------------------------------------------------------

def test_page_is_self_contained_and_holds_every_walk(tmp_path):
    path = write_viewer_html(tmp_path / "view.html", _floors(), _tracks(), title="Two walks")
    html = path.read_text(encoding="utf-8")
    # plotly.js inlined, no external source of any kind (script, stylesheet, image, frame).
    assert len(html) > 3_000_000 and "Plotly.newPlot" in html
    external = re.findall(r"<(?:script|link|img|iframe)\b[^>]*\b(?:src|href)\s*=\s*[\"']?(?:https?:)?//", html, re.I)
    assert external == []
    assert "<title>Two walks</title>" in html
    fig = _figure_json(html)
    metas = [t["meta"] for t in fig["data"]]
    assert metas.count("walk:walk A") == 6  # band, track, waypoints, fixes, ellipse at t, marker
    assert metas.count("walk:walk B") == 2  # track, marker: no sd, no waypoints, no fixes
    # The first walk and its floor are shown; the other walk and floor hidden.
    shown = {t["meta"] for t in fig["data"] if t["visible"]}
    assert shown == {"floor:F1", "walk:walk A"}
    sliders = fig["layout"]["sliders"]
    assert [s["visible"] for s in sliders] == [True, False]
    # Slider labels in seconds since the walk's start; the marker starts at the first sample.
    assert sliders[0]["steps"][0]["label"] == "0.0" and sliders[0]["steps"][-1]["label"] == "120.0"
    marker = [t for t in fig["data"] if t["meta"] == "walk:walk A" and t["name"] == "position at t"][0]
    assert marker["x"] == [round(20 + 17.0, 3)] and marker["y"] == [10.0]
    # The walk selector: one button per walk, each showing that walk's floor only.
    buttons = fig["layout"]["updatemenus"][0]["buttons"]
    assert [b["label"] for b in buttons] == ["walk A  (F1)", "walk B  (F2)"]
    vis_b = buttons[1]["args"][0]["visible"]
    assert {m for m, v in zip(metas, vis_b) if v} == {"floor:F2", "walk:walk B"}
    assert buttons[1]["args"][1]["sliders[1].visible"] is True and buttons[1]["args"][1]["sliders[0].visible"] is False
    # Equal aspect.
    assert fig["layout"]["yaxis"]["scaleanchor"] == "x" and fig["layout"]["yaxis"]["scaleratio"] == 1
    assert "P(on F1) = 0.50" in fig["layout"]["annotations"][0]["text"]


def test_long_walk_slider_is_decimated_and_file_stays_small(tmp_path):
    n = 50_000  # about 7 h of steps
    t = np.arange(n) * 0.5
    xy = np.c_[20 + 17 * np.cos(t / 200), 10 + 8 * np.sin(t / 200)]
    walk = ViewerTrack("long", "F1", t, xy, sd_m=np.ones((n, 2)))
    small = write_viewer_html(tmp_path / "small.html", _floors()[:1], [ViewerTrack("s", "F1", t[:2], xy[:2])])
    path = write_viewer_html(tmp_path / "long.html", _floors()[:1], [walk], max_slider_steps=300, max_ellipses=200)
    fig = _figure_json(path.read_text(encoding="utf-8"))
    steps = fig["layout"]["sliders"][0]["steps"]
    assert 250 <= len(steps) <= 302 and steps[0]["label"] == "0.0" and steps[-1]["label"] == f"{t[-1]:.1f}"
    # Above plotly.js: the track line (every sample) + 300 slider steps + 200 ellipses.
    extra = path.stat().st_size - small.stat().st_size
    assert extra < 2_500_000, extra


def test_one_sample_walk_and_markup_in_names(tmp_path):
    # One sample, zero spread, names with markup: a page all the same, the names escaped in the JSON.
    floor = ViewerFloor("F<1>", _floors()[0].outlines)
    walk = ViewerTrack("</script><b>x</b>", "F<1>", np.array([3.0]), np.array([[1.0, 2.0]]), sd_m=np.zeros((1, 2)))
    html = write_viewer_html(tmp_path / "v.html", [floor], [walk], title="</title><script>x").read_text()
    assert html.count("<script") == html.count("</script>") == 3  # plotly config, plotly.js, the plot
    fig = _figure_json(html)
    assert len(fig["layout"]["sliders"][0]["steps"]) == 1 and fig["layout"]["sliders"][0]["steps"][0]["label"] == "0.0"


def test_decimate_spreads_samples_in_time():
    t = np.r_[np.linspace(0, 10, 1000), np.linspace(10.01, 100, 100)]
    idx = decimate(t, 50)
    assert idx[0] == 0 and idx[-1] == len(t) - 1 and len(idx) <= 52 and np.all(np.diff(idx) > 0)
    # Evenly in time: no gap between kept samples much above (100 - 0) / 49 s.
    assert np.max(np.diff(t[idx])) < 2.2 * 100 / 49
    np.testing.assert_array_equal(decimate(t[:10], 50), np.arange(10))


def test_floor_from_plan():
    shop = np.array([[2, 2], [4, 2], [4, 4], [2, 4]], float)
    outline = np.array([[0, 0], [10, 0], [10, 8], [0, 8]], float)
    plan = fusion.FloorPlan([fusion.FloorGeometry(3, [outline], [shop], np.zeros((0, 4))),
                             fusion.FloorGeometry(5, [outline * 2], [], np.array([[1.0, 1.0, 5.0, 1.0]]))])
    f0 = viewer_floor_from_plan(plan, 0, name="ground")
    assert f0.name == "ground" and len(f0.outlines) == 1 and len(f0.obstacles) == 1 and f0.walls is None
    np.testing.assert_allclose(np.sort(f0.obstacles[0], axis=0), np.sort(shop, axis=0))
    f1 = viewer_floor_from_plan(plan, 1)
    assert f1.name == "floor 5" and f1.walls.shape == (1, 4)
    with pytest.raises(ValueError, match="floor_index"):
        viewer_floor_from_plan(plan, 2)
    with pytest.raises(TypeError, match="plan"):
        viewer_floor_from_plan("plan.geojson")


def _with(track, **changes):
    d = dict(track.__dict__)
    d.update(changes)
    return ViewerTrack(**d)


@pytest.mark.parametrize("change, argument", [
    (dict(floor="F9"), r"tracks\[0\]\.floor"),
    (dict(xy_m=np.full((600, 2), np.nan)), r"tracks\[0\]\.xy_m'.*NaN"),
    (dict(xy_m=np.zeros((599, 2))), r"tracks\[0\]\.xy_m'.*shape"),
    (dict(t_s=np.linspace(10, 0, 600)), r"tracks\[0\]\.t_s'.*non-decreasing"),
    (dict(t_s=np.zeros(0), xy_m=np.zeros((0, 2))), r"tracks\[0\]\.t_s"),
    (dict(sd_m=-np.ones((600, 2))), r"tracks\[0\]\.sd_m'.*negative"),
    (dict(sd_m=np.ones((600, 3))), r"tracks\[0\]\.sd_m"),
    (dict(waypoints_xy_m=None), r"tracks\[0\]\.waypoints_t_s'.*both"),
    (dict(fixes_xy_m=np.zeros((3, 2))), r"tracks\[0\]\.fixes_xy_m'.*shape"),
    (dict(floor_probability=np.full(600, 1.5)), r"tracks\[0\]\.floor_probability"),
    (dict(xy_correlation=np.full(600, 2.0)), r"tracks\[0\]\.xy_correlation"),
    (dict(name=""), r"tracks\[0\]\.name"),
])
def test_bad_track_names_the_argument(tmp_path, change, argument):
    tracks = _tracks()
    tracks[0] = _with(tracks[0], **change)
    with pytest.raises(ValueError, match=argument):
        write_viewer_html(tmp_path / "v.html", _floors(), tracks)
    assert not list(tmp_path.iterdir())  # nothing written


def test_bad_floors_and_arguments(tmp_path):
    floors, tracks = _floors(), _tracks()
    with pytest.raises(ValueError, match=r"floors\[1\]\.name'.*twice"):
        write_viewer_html(tmp_path / "v.html", [floors[0], ViewerFloor("F1", floors[1].outlines)], tracks[:1])
    with pytest.raises(ValueError, match=r"tracks\[1\]\.name'.*twice"):
        write_viewer_html(tmp_path / "v.html", floors, [tracks[0], _with(tracks[1], name="walk A")])
    with pytest.raises(ValueError, match=r"floors\[0\]\.outlines\[0\]'.*infinite"):
        write_viewer_html(tmp_path / "v.html", [ViewerFloor("F1", [np.array([[0, 0], [1, np.inf], [1, 1]])])],
                          tracks[:1])
    with pytest.raises(ValueError, match=r"floors\[0\]\.outlines'.*at least one"):
        write_viewer_html(tmp_path / "v.html", [ViewerFloor("F1", [])], tracks[:1])
    with pytest.raises(ValueError, match="'tracks': is empty"):
        write_viewer_html(tmp_path / "v.html", floors, [])
    with pytest.raises(TypeError, match=r"tracks\[0\]"):
        write_viewer_html(tmp_path / "v.html", floors, [{"name": "x"}])
    with pytest.raises(ValueError, match="'path'.*does not exist"):
        write_viewer_html(tmp_path / "missing" / "v.html", floors, tracks)
    with pytest.raises(ValueError, match="max_slider_steps"):
        write_viewer_html(tmp_path / "v.html", floors, tracks, max_slider_steps=1)
    assert not list(tmp_path.iterdir())


def test_inputs_not_modified_and_write_is_atomic(tmp_path, monkeypatch):
    tracks = _tracks()
    before = [tr.xy_m.copy() for tr in tracks]
    path = tmp_path / "v.html"
    path.write_text("previous page")
    import indoorloc.fusion.viewer as viewer

    def failing_replace(src, dst):
        raise OSError("disk full (simulated)")
    monkeypatch.setattr(viewer.os, "replace", failing_replace)
    with pytest.raises(OSError, match="simulated"):
        write_viewer_html(path, _floors(), tracks)
    assert path.read_text() == "previous page" and sorted(p.name for p in tmp_path.iterdir()) == ["v.html"]
    monkeypatch.undo()
    write_viewer_html(path, _floors(), tracks)
    assert path.stat().st_size > 1_000_000 and sorted(p.name for p in tmp_path.iterdir()) == ["v.html"]
    umask = os.umask(0o022)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask  # not the temporary file's 0600
    for tr, xy in zip(tracks, before):
        np.testing.assert_array_equal(tr.xy_m, xy)


def test_import_indoorloc_does_not_need_plotly():
    code = ("import sys, indoorloc, indoorloc.fusion, indoorloc.fusion.viewer; "
            "assert 'plotly' not in sys.modules, 'plotly imported'")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60, env=dict(os.environ))


# ---- in a real browser ---------------------------------------------------------------------

def _browser_missing_reason():
    missing = [p for p in (CHROMIUM, CHROMEDRIVER) if not os.path.isfile(p)]
    try:
        import selenium  # noqa: F401
    except ImportError:
        missing.append("the selenium package")
    return ", ".join(missing)


@pytest.fixture(scope="module")
def browser():
    missing = _browser_missing_reason()
    if missing:
        if os.environ.get("CI") == "true":
            pytest.fail(f"browser test: missing {missing} (make test installs them: apt chromium chromium-driver, "
                        f"pip selenium)")
        pytest.skip(f"browser test: missing {missing} (apt-get install chromium chromium-driver; pip install selenium)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common import selenium_manager

    def no_download(*args, **kwargs):
        raise AssertionError("selenium-manager must not run (it would download a driver)")
    patch = pytest.MonkeyPatch()
    patch.setattr(selenium_manager.SeleniumManager, "binary_paths", no_download)
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,1000", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    driver = webdriver.Chrome(service=Service(executable_path=CHROMEDRIVER), options=options)
    driver.set_page_load_timeout(30)
    driver.set_script_timeout(10)
    try:
        yield driver
    finally:
        driver.quit()
        patch.undo()


_STATE_JS = """
var gd = document.getElementById('indoorloc-viewer');
var out = {};
gd._fullData.forEach(function (t, i) {
  if (t.name !== 'position at t' || !t.visible) return;
  var pt = document.querySelector('.trace' + t.uid + ' .point');
  out = {walk: t.meta, x: t.x[0], y: t.y[0], transform: pt ? pt.getAttribute('transform') : null};
});
out.sliders = gd._fullLayout.sliders.map(function (s) { return s.visible; });
out.floors = gd._fullData.filter(function (t) { return t.visible === true && t.meta.indexOf('floor:') === 0; })
                          .map(function (t) { return t.meta; });
out.status = Array.from(document.querySelectorAll('.annotation-text')).map(function (e) { return e.textContent; });
return out;
"""


def _wait(driver, predicate, what, timeout_s=10.0):
    from selenium.webdriver.support.ui import WebDriverWait
    WebDriverWait(driver, timeout_s, poll_frequency=0.1).until(lambda d: predicate(d), message=what)


def _visible(elements):
    """The elements drawn with a size (plotly's transparent hit areas count: is_displayed() is
    False for an opacity of 0)."""
    return [e for e in elements if e.size["width"] > 0 and e.size["height"] > 0]


def test_page_in_chromium(browser, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    tracks = _tracks()
    page = write_viewer_html(tmp_path / "view.html", _floors(), tracks, title="Two walks")
    browser.get_log("browser")  # drop anything logged before this page
    browser.get_log("performance")
    browser.get(page.as_uri())
    _wait(browser, lambda d: d.execute_script(
        "var gd = document.getElementById('indoorloc-viewer'); return !!(gd && gd._fullLayout && "
        "document.querySelector('.slider-rail-touch-rect'));"), "the plot was not drawn")
    state0 = browser.execute_script(_STATE_JS)
    assert state0["walk"] == "walk:walk A" and state0["floors"] == ["floor:F1", "floor:F1"]
    assert state0["sliders"] == [True, False] and state0["transform"]
    assert state0["x"] == pytest.approx(37.0) and state0["y"] == pytest.approx(10.0)

    # Drag the slider: click the rail at three quarters of its length.
    rail = _visible(browser.find_elements(By.CSS_SELECTOR, ".slider-rail-touch-rect"))[0]
    ActionChains(browser).move_to_element_with_offset(rail, int(rail.size["width"] * 0.25), 0).click().perform()
    _wait(browser, lambda d: d.execute_script(_STATE_JS)["x"] != state0["x"], "the slider did not move the marker")
    state1 = browser.execute_script(_STATE_JS)
    assert state1["transform"] != state0["transform"]  # the drawn point moved, not only the data
    # The marker sits on the track sample of the slider's time, shown in the status line.
    t_shown = float(re.search(r"t = ([0-9.]+) s", state1["status"][0]).group(1))
    assert 60.0 < t_shown < 120.0
    tr = tracks[0]
    i = int(np.argmin(np.abs(tr.t_s - tr.t_s[0] - t_shown)))
    assert (state1["x"], state1["y"]) == pytest.approx(tuple(tr.xy_m[i]), abs=0.6)

    # Switch walk with the selector: walk B on floor F2, its own slider.
    ActionChains(browser).click(_visible(browser.find_elements(By.CSS_SELECTOR, ".updatemenu-header"))[0]).perform()
    _wait(browser, lambda d: len(_visible(d.find_elements(By.CSS_SELECTOR, ".updatemenu-dropdown-button"))) >= 2,
          "the walk selector did not open")
    option = [b for b in _visible(browser.find_elements(By.CSS_SELECTOR, ".updatemenu-dropdown-button")) if "walk B" in b.text]
    assert option, "no 'walk B' in the walk selector"
    ActionChains(browser).click(option[0]).perform()
    _wait(browser, lambda d: d.execute_script(_STATE_JS)["walk"] == "walk:walk B", "the walk selector did not switch")
    state2 = browser.execute_script(_STATE_JS)
    assert state2["floors"] == ["floor:F2"] and state2["sliders"] == [False, True]
    assert state2["x"] == pytest.approx(25.0) and state2["y"] == pytest.approx(15.0)

    browser.save_screenshot(str(tmp_path / "viewer.png"))
    assert (tmp_path / "viewer.png").stat().st_size > 10_000

    # No console error, and no request left the page (every request was the file itself).
    errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    assert errors == []
    urls = set()
    for entry in browser.get_log("performance"):
        msg = json.loads(entry["message"])["message"]
        if msg["method"] == "Network.requestWillBeSent":
            urls.add(msg["params"]["request"]["url"])
    assert urls and all(u.startswith(("file:", "data:", "blob:")) for u in urls), urls
