"""The WiFi studies' shared folds and table (experiments.wifi_study_folds)."""
import numpy as np

from indoorloc.experiments.wifi_study_folds import floor_folds, lofo_markdown


def _stats(m):
    return {"mean_m": m, "median_m": m / 2, "p90_m": 2 * m}


def test_lofo_markdown_has_a_row_per_floor_the_choices_and_the_pooled_held_out_figure():
    r = {"seed": 1, "lofo": {"all_floor_choice": "k=3", "held_out_pooled": _stats(5.0)},
         "per_floor": {f: {"a": _stats(1.0), "b": _stats(2.0), "held_out": {**_stats(3.0), "chosen": f"k={i}"}}
                       for i, f in enumerate(["F1", "F2"])}}
    text = lofo_markdown(r, "Seed 1", [("A", "a"), ("B", "b")], held_out_head="held")
    lines = text.splitlines()
    assert lines[0] == "Seed 1; all-floor choice: `k=3`"
    assert lines[2] == "| floor | A | B | held | LOFO choice |"
    assert lines[3] == "|---|---|---|---|---|"
    assert lines[4] == "| F1 | 1.00 / 0.50 / 2.0 | 2.00 / 1.00 / 4.0 | 3.00 / 1.50 / 6.0 | `k=0` |"
    assert lines[-1] == "| pooled (held out) | | | 5.00 / 2.50 / 10.0 | |"
    assert all(line.count("|") == 6 for line in lines[2:])


def test_floor_folds_split_every_walk_once_as_fusion_evaluate_does(shared_data):
    root = shared_data / "fusion" / "ilc2020_site2"
    seen = []
    for fl, fold in floor_folds(root, "F8", seed=0):
        # The training database holds the floor's other walks (walk_index counts the training walks).
        n_train = np.unique(fold.database.walk_index[fold.database.floors == fl.number]).size
        ids = [fw.walk.walk_id for fw in fold.walks]
        assert n_train + len(ids) == len(fl.walks)
        assert all(fw.coverage_m.shape == fw.waypoint_t_s.shape for fw in fold.walks)
        seen += ids
    assert sorted(seen) == sorted(w.walk_id for w in fl.walks)
