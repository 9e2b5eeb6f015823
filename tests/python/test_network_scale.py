"""The network subsystem's scale path: streaming block-tridiagonal solver on the linearised
INS/GPS network (indoorloc._core.network), checked against scipy on the same equations."""

import sys
from pathlib import Path

import numpy as np
import pytest

from indoorloc._core import network

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import network_peers  # noqa: E402

NET = network.LinearInsNetworkOptions  # the network's size and noise model


@pytest.mark.parametrize("rule", ["leapfrog", "trapezoidal"])
def test_solution_and_gravity_covariances_match_scipy_and_the_dense_inverse(rule):
    eq = network.linear_ins_equations(NET(imu_rate_hz=50.0, duration_s=2.0, rule=rule))
    E = int(eq.imu_epochs)
    ours = network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, rule=rule), keep_gravity_estimate=True)
    assert ours.imu_epochs == E and ours.unknowns == 18 * E
    assert ours.max_abs_error < 1e-6  # noise-free observations: the truth comes back
    A, b = network_peers.sparse_normal_system(eq)
    dense = A.toarray()
    x = np.linalg.solve(dense, b)
    np.testing.assert_allclose(ours.gravity_estimate, x.reshape(E, 18)[:, 15:], rtol=0, atol=1e-9)
    inverse = np.linalg.inv(dense)
    idx = np.arange(E)[:, None] * 18 + 15 + np.arange(3)[None, :]
    np.testing.assert_allclose(ours.gravity_sigma, np.sqrt(np.diag(inverse)[idx]), rtol=1e-6)
    # Checkpointed: identical numbers, twice the assembler calls (the middle block of the twisted
    # order once).
    again = network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, rule=rule), keep_gravity_estimate=True, checkpoint_interval=5)
    np.testing.assert_array_equal(again.gravity_sigma, ours.gravity_sigma)
    assert again.assembler_calls == 2 * ours.assembler_calls - 1
    # Two threads (one per chain): bit-identical.
    two = network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, rule=rule), keep_gravity_estimate=True, checkpoint_interval=5, num_threads=2)
    np.testing.assert_array_equal(two.gravity_sigma, ours.gravity_sigma)
    np.testing.assert_array_equal(two.gravity_estimate, ours.gravity_estimate)


def test_normal_blocks_rebuild_the_sparse_matrix():
    D, L, r = network.linear_ins_normal_blocks(NET(imu_rate_hz=50.0, duration_s=1.0))
    A, b = network_peers.sparse_normal_system(network.linear_ins_equations(NET(imu_rate_hz=50.0, duration_s=1.0)))
    n, bs, _ = D.shape
    dense = A.toarray()
    for j in range(n):
        np.testing.assert_allclose(D[j], dense[j * bs:(j + 1) * bs, j * bs:(j + 1) * bs], rtol=1e-12, atol=1e-6)
        if j > 0:
            np.testing.assert_allclose(L[j], dense[j * bs:(j + 1) * bs, (j - 1) * bs:j * bs], rtol=1e-12, atol=1e-6)
    np.testing.assert_allclose(r.ravel(), b, rtol=1e-12, atol=1e-9)


def test_leapfrog_without_a_datum_for_the_odd_chain_is_reported():
    with pytest.raises(RuntimeError, match="rank-deficient"):
        network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0, rule="leapfrog", prior_epochs=1))
    out = network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0, rule="trapezoidal", prior_epochs=1))
    assert out.max_abs_error < 1e-5


@pytest.mark.parametrize("rule", ["leapfrog", "trapezoidal"])
def test_qr_method_matches_the_cholesky_the_truth_and_the_dense_inverse(rule):
    chol = network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, rule=rule), keep_gravity_estimate=True)
    qr = network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, rule=rule), keep_gravity_estimate=True, method="qr")
    assert qr.unknowns == chol.unknowns
    assert qr.max_abs_error < 1e-9
    np.testing.assert_allclose(qr.gravity_estimate, chol.gravity_estimate, rtol=0, atol=1e-9)
    np.testing.assert_allclose(qr.gravity_sigma, chol.gravity_sigma, rtol=1e-6)
    assert qr.max_abs_error_by_unknown.shape == (18,)
    assert 0 <= qr.min_relative_pivot_block < qr.num_blocks
    assert 0 <= qr.min_relative_pivot_unknown < qr.block_size
    again = network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, rule=rule), keep_gravity_estimate=True, method="qr", checkpoint_interval=5)
    np.testing.assert_array_equal(again.gravity_sigma, qr.gravity_sigma)
    np.testing.assert_array_equal(again.gravity_estimate, qr.gravity_estimate)


def test_qr_keeps_the_digits_the_normal_equations_lose():
    # 200 Hz x 300 s, 5 Hz GPS, trapezoidal: the normal equations square the condition of the
    # heading-error mode (measured max error: Cholesky 5e-6, QR 1e-10).
    net = NET(imu_rate_hz=200.0, duration_s=300.0, gps_rate_hz=5.0, rule="trapezoidal")
    chol = network.solve_linear_ins_network(net, gravity_covariance=False, checkpoint_interval=512)
    qr = network.solve_linear_ins_network(net, gravity_covariance=False, checkpoint_interval=512, method="qr")
    assert qr.max_abs_error < 1e-8
    assert qr.max_abs_error < 1e-2 * chol.max_abs_error


def test_qr_refuses_the_leapfrog_datum_defect_and_bad_method():
    with pytest.raises(RuntimeError, match=r"at block \d+, unknown \d+ .*rank-deficient"):
        network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0, rule="leapfrog", prior_epochs=1), method="qr")
    with pytest.raises(ValueError, match="method"):
        network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0), method="lu")
    with pytest.raises(ValueError, match="pivot_tolerance"):
        network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0), method="qr", pivot_tolerance=2.0)
    for method in ("cholesky", "qr"):  # the message names the argument, not 'options'
        with pytest.raises(ValueError, match="argument 'pivot_tolerance': must be in"):
            network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0), pivot_tolerance=float("nan"), method=method)
    with pytest.raises(ValueError, match="pivot_tolerance"):
        network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0), pivot_tolerance=-1.0)


def test_bad_arguments_name_the_argument():
    with pytest.raises(ValueError, match="rule"):
        network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0, rule="euler"))
    with pytest.raises(ValueError, match="checkpoint_interval"):
        network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=5.0), checkpoint_interval=-2)
    with pytest.raises(ValueError, match="options"):
        network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=-1.0))


def test_crossover_ties_are_solved_and_keep_the_truth():
    out = network.solve_linear_ins_network_with_crossovers(NET(imu_rate_hz=50.0, duration_s=40.0, gps_rate_hz=2.0), lines=5, cross_lines=4)
    assert out.crossings == 20 and out.ties == 60
    assert out.pcg_converged and out.pcg_iterations > 0
    assert out.gravity_rmse < 1e-8
    with pytest.raises(ValueError, match="lines"):
        network.solve_linear_ins_network_with_crossovers(NET(imu_rate_hz=50.0, duration_s=40.0, gps_rate_hz=2.0), lines=0, cross_lines=4)


@pytest.mark.parametrize("one_step", [True, False])
def test_ceres_peer_solves_the_same_network(one_step):
    ours = network.solve_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=4.0), keep_gravity_estimate=True, gravity_covariance=False)
    peer = network.solve_linear_ins_network_ceres(NET(imu_rate_hz=50.0, duration_s=4.0), one_gauss_newton_step=one_step)
    assert peer.x.shape == (ours.imu_epochs, 18)
    assert "SPARSE_NORMAL_CHOLESKY" in peer.linear_solver
    np.testing.assert_allclose(peer.x[:, 15:], ours.gravity_estimate, rtol=0, atol=1e-8 if one_step else 1e-6)
    if one_step:
        assert peer.iterations == 1
    with pytest.raises(ValueError, match="rule"):
        network.solve_linear_ins_network_ceres(NET(imu_rate_hz=50.0, duration_s=4.0, rule="euler"))


# --- Case 4: repeated passes folded into the band ---------------------------------------------

def test_folded_repeated_pass_network_matches_the_dense_tied_solve():
    from indoorloc import network as facade

    d = facade.solve_repeated_pass_network(50.0, 2.0, 2.0, num_ties=60, num_gupts=4, keep_gravity_estimate=True,
                                           checkpoint_interval=0)
    E = int(d.imu_epochs)
    assert d.ties == 60 and d.gupts == 4 and d.folded_block_size == 72
    assert d.max_abs_error < 1e-6 and d.gravity_rmse < 1e-9  # noise-free: the truth comes back
    assert isinstance(d.gravity_sigma, np.ndarray) and d.gravity_sigma.shape == (E, 3)
    # Dense reference in the original order: the banded normal matrix + the same ties and GUPTs.
    D, L, rhs = network.linear_ins_normal_blocks(NET(imu_rate_hz=50.0, duration_s=2.0, gps_rate_hz=2.0, rule="leapfrog"))
    n, b = D.shape[0], D.shape[1]
    A = np.zeros((n * b, n * b))
    for j in range(n):
        A[j * b:(j + 1) * b, j * b:(j + 1) * b] += D[j]
        if j:
            A[j * b:(j + 1) * b, (j - 1) * b:j * b] += L[j]
            A[(j - 1) * b:j * b, j * b:(j + 1) * b] += L[j].T
    landing = np.arange(E - 2, E) * 18 + 15 + np.arange(3)[:, None]
    A[landing, landing] -= 1e10  # these blocks hold the default landing GUPT; the folded solve has none
    # The layout: every mirror pair (t, E-1-t) (P = E/2 = 51 of them), then 9 ties to the
    # mirror's neighbour (t, E-2-t), t = i Q / 9 with Q = (E-1)//2.
    P, Q, w = E // 2, (E - 1) // 2, 1e10
    pairs = [(t, E - 1 - t) for t in range(P)] + [((i * Q) // 9, E - 2 - (i * Q) // 9) for i in range(9)]
    for t, m in pairs:
        a, c = t * 18 + 17, m * 18 + 17
        A[a, a] += w; A[c, c] += w; A[a, c] -= w; A[c, a] -= w
    for i in range(4):
        u = ((2 * i + 1) * E) // 8 * 18 + 17
        A[u, u] += w
    var = np.diag(np.linalg.inv(A))[np.arange(E)[:, None] * 18 + 15 + np.arange(3)[None, :]]
    np.testing.assert_allclose(d.gravity_sigma, np.sqrt(var), rtol=1e-6)
    two = facade.solve_repeated_pass_network(50.0, 2.0, 2.0, num_ties=60, num_gupts=4, keep_gravity_estimate=True,
                                             checkpoint_interval=0, num_threads=2)
    np.testing.assert_array_equal(two.gravity_sigma, d.gravity_sigma)
    np.testing.assert_array_equal(two.gravity_estimate, d.gravity_estimate)


def test_folded_network_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="num_ties"):
        network.solve_folded_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, gps_rate_hz=2.0), num_ties=10**6)
    with pytest.raises(ValueError, match="sigma_xover_mps2"):
        network.solve_folded_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, gps_rate_hz=2.0), num_ties=10, sigma_xover_mps2=float("nan"))
    with pytest.raises(ValueError, match="checkpoint_interval"):
        network.solve_folded_linear_ins_network(NET(imu_rate_hz=50.0, duration_s=2.0, gps_rate_hz=2.0), num_ties=10, checkpoint_interval=-1)


def test_scale_results_are_typed_and_their_former_dict_reading_warns():
    """Each scale function returns a typed read-only result (bindings/bind_network_scale_results.cc):
    attributes and to_dict() are quiet; reading it as the former dict still works for one release
    and warns (docs/api_changes.md); it pickles as that dict (Dask)."""
    import pickle
    import warnings

    results = [
        network.solve_linear_ins_network(NET(imu_rate_hz=10.0, duration_s=5.0), keep_gravity_estimate=True),
        network.solve_folded_linear_ins_network(NET(imu_rate_hz=10.0, duration_s=5.0), num_ties=10, num_gupts=2),
        network.solve_linear_ins_network_with_crossovers(NET(imu_rate_hz=10.0, duration_s=60.0, gps_rate_hz=1.0, rule="leapfrog"), 3, 3),
        network.solve_linear_ins_network_ceres(NET(imu_rate_hz=10.0, duration_s=5.0), one_gauss_newton_step=True),
        network.linear_ins_equations(NET(imu_rate_hz=10.0, duration_s=5.0)),
    ]
    names = ["LinearInsNetworkResult", "FoldedNetworkResult", "CrossoverNetworkResult", "LinearInsCeresResult",
             "LinearInsEquations"]
    assert [type(r).__name__ for r in results] == names
    for r in results:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            plain = r.to_dict()
            assert list(plain) == list(type(r)._fields) and plain["imu_epochs"] == r.imu_epochs > 0
        with pytest.raises(AttributeError):
            r.imu_epochs = 1  # read-only
        with pytest.warns(DeprecationWarning, match=rf"reading a {type(r).__name__} as a dict \(result\[key\]\)"):
            assert r["imu_epochs"] == r.imu_epochs
        with pytest.warns(DeprecationWarning, match=r"items\(\)"):
            assert [k for k, _ in r.items()] == list(plain)
        with pytest.warns(DeprecationWarning, match=r"key in result"):
            assert "imu_epochs" in r
        back = pickle.loads(pickle.dumps(r))
        assert isinstance(back, dict) and back["imu_epochs"] == r.imu_epochs
    np.testing.assert_array_equal(results[0].gravity_estimate, results[0].to_dict()["gravity_estimate"])
    assert results[4].J[0].shape == (18, 18) and len(results[4].J) == len(results[4].offsets)


def test_scale_functions_take_the_network_once_and_the_former_keywords_warn():
    """The network's size and noise model are one LinearInsNetworkOptions (defaults read from C++);
    the former calls with imu_rate_hz, duration_s, ... as arguments still work, warn, and give the
    same numbers."""
    assert NET().to_dict()["imu_rate_hz"] == 200.0 and NET(rule="trapezoidal").rule == "trapezoidal"
    new = network.solve_linear_ins_network(NET(imu_rate_hz=20.0, duration_s=3.0, prior_epochs=3),
                                           keep_gravity_estimate=True)
    with pytest.warns(DeprecationWarning, match=r"solve_linear_ins_network\(imu_rate_hz, duration_s"):
        old = network.solve_linear_ins_network(20.0, 3.0, keep_gravity_estimate=True, prior_epochs=3)
    np.testing.assert_array_equal(old.gravity_estimate, new.gravity_estimate)
    with pytest.warns(DeprecationWarning):  # positional, in the former order (sigma_gupt_mps2 is the network's)
        folded = network.solve_folded_linear_ins_network(20.0, 3.0, 2.0, "leapfrog", 10, 2, 1e-5, 2e-5)
    again = network.solve_folded_linear_ins_network(NET(imu_rate_hz=20.0, duration_s=3.0, gps_rate_hz=2.0,
                                                        sigma_gupt_mps2=2e-5), 10, 2, 1e-5)
    assert folded.max_abs_error == again.max_abs_error and folded.gupts == 2
    with pytest.raises(ValueError, match="'rule'"):
        NET(rule="euler")
    with pytest.raises(TypeError, match="incompatible function arguments"):
        network.linear_ins_equations(NET(), 2)
