"""Every study's command line (``python -m indoorloc.experiments.<study>``) takes ``--quiet``
(CONVENTIONS rule 12: progress stays quiet under CI or ``--quiet``), and ``--quiet`` turns the
process's progress output off."""

import importlib

import pytest

from indoorloc import progress

#: Studies whose ``main(argv)`` parses a command line with argparse (the floor studies through
#: ``study_cli.run_study``). Not listed: ``pdr_handheld`` (``main`` takes Python arguments).
STUDIES = ["floor_change_study", "floor_identification_study", "fusion_live_accuracy", "fusion_uncertainty", "ilc_signal_map",
           "mapmatch_noise_tuning", "pdr_gait_sweep", "pdr_health_signals", "pdr_low_motion", "pdr_zupt_cv",
           "site_growth", "wifi_interpolated_refs", "wifi_matcher_agreement", "wifi_matcher_study",
           "wifi_previous_matcher", "wifi_wknn_wide_k"]


@pytest.mark.parametrize("study", STUDIES)
def test_every_study_cli_accepts_quiet(study, capsys):
    module = importlib.import_module(f"indoorloc.experiments.{study}")
    with pytest.raises(SystemExit) as ended:
        module.main(["--help"])
    assert ended.value.code == 0
    assert "--quiet" in capsys.readouterr().out


def test_quiet_silences_the_progress_of_a_study(monkeypatch, capsys):
    from indoorloc.experiments import pdr_low_motion as lm

    seen = {}

    def stop(*args, **kwargs):  # stand-in for the loading: record the switch and end the run
        seen["quiet"] = progress._quiet
        raise RuntimeError("stop here")

    monkeypatch.setattr(lm, "list_pyshoe_trials", stop)
    try:
        with pytest.raises(RuntimeError, match="stop here"):
            lm.main(["--data-root", "nowhere", "--quiet"])
        assert seen["quiet"] is True
        assert not progress.enabled() and not progress.lines_enabled()
    finally:
        progress.set_quiet(False)


@pytest.mark.parametrize("study", ["floor_change_study", "floor_identification_study"])
def test_a_missing_data_folder_is_one_error_line(study, tmp_path, capsys):
    # A study sharing study_cli: a folder that does not exist is an 'error:' line and exit code 2.
    module = importlib.import_module(f"indoorloc.experiments.{study}")
    missing = tmp_path / "no_such_site"
    try:
        assert module.main(["--data-root", str(missing), "--quiet"]) == 2
    finally:
        progress.set_quiet(False)
    err = capsys.readouterr().err
    assert err.startswith("error: ") and str(missing) in err
