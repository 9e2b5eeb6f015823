"""The live-accuracy study (experiments.fusion_live_accuracy) on a synthetic site written in the
competition's format: it scores the evaluation's own methods on the evaluation's folds and models,
so its ``batch_filter`` and ``live`` are ``fusion evaluate``'s ``fusion_unknown_start`` and
``fusion_live`` waypoint for waypoint."""

import numpy as np
import pytest

from indoorloc.experiments import fusion_live_accuracy as la
from indoorloc.experiments import fusion_real as fr
from indoorloc.simulate.ilc_site import write_ilc_site


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    return write_ilc_site(tmp_path_factory.mktemp("ilc_live_acc") / "site", floors=("F1",), walks_per_floor=8, seed=5)


def test_the_study_scores_the_evaluations_methods(site, tmp_path):
    result = la.compute(str(site), ["F1"], [0])
    ev = fr.evaluate(site, ["F1"], fr.RealSettings(floor_identification=False))
    pooled = result["pooled"]
    assert set(pooled) == set(la.METHODS)
    for study_name, eval_name in (("batch_filter", "fusion_unknown_start"), ("live", "fusion_live")):
        assert pooled[study_name]["n"] == ev["methods"][eval_name]["n_waypoints"]
        assert pooled[study_name]["mean_m"] == pytest.approx(ev["methods"][eval_name]["mean_m"], abs=1e-9)
    first = result["live_first_position_s"]
    assert first["walks"] == 8 and 0.0 < first["median"] <= first["p90"] <= first["max"]
    assert first["median"] == pytest.approx(ev["methods"]["fusion_live"]["first_position"]["median_s"])
    assert result["lofo_window"] == {}   # one floor: no other floor to choose the window on
    # The command line writes the JSON and the Markdown.
    out, md = tmp_path / "r.json", tmp_path / "r.md"
    assert la.main(["--data-root", str(site), "--floors", "F1", "--json", str(out), "--markdown", str(md),
                    "--quiet"]) == 0
    assert "| pooled |" in md.read_text() and '"live_first_position_s"' in out.read_text()
