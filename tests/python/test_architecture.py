"""The layout rule of docs/architecture.md ("Where a concept lives"), checked on the tree.

A concept ``foo`` of subsystem ``bar`` is the public header ``cpp/include/indoorloc/bar/foo.h``,
its source ``cpp/src/bar/foo.cc``, its C++ test ``tests/cpp/bar/foo_test.cc`` and a Python test
``tests/python/test_bar*.py``; the subsystem's Python side is the package ``python/indoorloc/bar/``
(its facade in ``__init__.py``), mirroring ``cpp/include/indoorloc/bar/``. A concept whose C++ test lives in a sibling's test file is
listed in ``TESTED_WITH`` (the test checks that file includes the header), so that a new header
without a test fails here.
"""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HEADERS = sorted((ROOT / "cpp" / "include" / "indoorloc").glob("*/*.h"))
SUBSYSTEMS = sorted({h.parent.name for h in HEADERS})

#: Concepts tested inside a sibling concept's test file (what they serve is tested there): header
#: -> that test file.
TESTED_WITH = {
    "core/interrupt": "core/validate_test.cc",
    "core/options": "core/check_test.cc",
    "fusion/backward_smoother": "fusion/particle_tracker_test.cc",
    "fusion/track": "fusion/particle_tracker_test.cc",
    "mapmatch/monte_carlo": "mapmatch/particle_map_matcher_test.cc",
    "mapmatch/trajectory_simulator": "mapmatch/particle_map_matcher_test.cc",
    "network/gravity": "network/residuals_test.cc",
    "network/kalman_smoother": "network/network_adjustment_test.cc",
    "pdr/step_detection": "pdr/zupt_ekf_test.cc",
    "pdr/stride_count": "pdr/zero_velocity_test.cc",
    # The catalog is the analog HMM's input: built and checked by every analog HMM test (through
    # indoorloc/analog/analog_hmm.h, which includes it).
    "analog/catalog": "analog/analog_hmm_test.cc",
}


def _concept(header: Path) -> str:
    return f"{header.parent.name}/{header.stem}"


@pytest.mark.parametrize("header", HEADERS, ids=[_concept(h) for h in HEADERS])
def test_concept_has_its_source_and_cpp_test(header):
    concept = _concept(header)
    subsystem, name = concept.split("/")
    assert (ROOT / "cpp" / "src" / subsystem / f"{name}.cc").exists(), f"{concept}: no cpp/src/{concept}.cc"
    own_test = ROOT / "tests" / "cpp" / subsystem / f"{name}_test.cc"
    if concept in TESTED_WITH:
        assert not own_test.exists(), f"{concept} has its own test now: remove it from TESTED_WITH"
        sibling = ROOT / "tests" / "cpp" / TESTED_WITH[concept]
        assert sibling.exists(), f"{concept}: {sibling} is missing"
        text = sibling.read_text()
        included = f'"indoorloc/{concept}.h"' in text
        if concept == "analog/catalog":
            included = included or '"indoorloc/analog/analog_hmm.h"' in text
        assert included, f"{sibling.name} does not include the header of {concept}"
    else:
        assert own_test.exists(), f"{concept}: no tests/cpp/{concept}_test.cc (or list it in TESTED_WITH)"


@pytest.mark.parametrize("subsystem", SUBSYSTEMS)
def test_subsystem_has_a_package_and_python_tests(subsystem):
    package = ROOT / "python" / "indoorloc"
    assert (package / subsystem / "__init__.py").exists(), (
        f"no Python package python/indoorloc/{subsystem}/ mirroring cpp/include/indoorloc/{subsystem}/")
    assert not (package / f"{subsystem}.py").exists(), (
        f"python/indoorloc/{subsystem}.py beside the package: the facade is {subsystem}/__init__.py")
    assert list((ROOT / "tests" / "python").glob(f"test_{subsystem}*.py")), f"no tests/python/test_{subsystem}*.py"


def test_every_python_subsystem_package_has_its_cpp_folder():
    """The mirror the other way: a Python package named like a subsystem has a C++ folder
    (io, simulate, experiments, cli and data are the Python-only packages of docs/architecture.md)."""
    python_only = {"io", "simulate", "experiments", "cli", "data", "_core"}
    # Deprecated aliases of moved modules (docs/api_changes.md), removed after one release.
    aliases = {"wifi_crowdsource", "wifi_fixes"}
    packages = {p.parent.name for p in (ROOT / "python" / "indoorloc").glob("*/__init__.py")}
    assert packages - python_only - aliases == set(SUBSYSTEMS)


def test_tested_with_lists_only_existing_headers():
    concepts = {_concept(h) for h in HEADERS}
    assert set(TESTED_WITH) <= concepts, f"stale entries: {set(TESTED_WITH) - concepts}"
