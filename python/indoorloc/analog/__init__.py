"""Exemplar-based (analog) hidden Markov models (paper 001, Lguensat et al., EUSIPCO 2016).

- :class:`Catalog`: (analog, successor) pairs from historical trajectories, with lag embedding.
- :class:`AnalogHMM`: sparse kNN transitions (eq. 4) and Gaussian observations (eq. 5);
  ``smooth`` (exact or truncated forward-backward: posterior mean, MPM) and ``viterbi``.
- :func:`forward_backward`, :func:`viterbi`: the same algorithms for any HMM with K successors per
  state (used to compare with hmmlearn and to test against brute force).
"""

from __future__ import annotations

from indoorloc._core.analog import AnalogHMM, Catalog, forward_backward, viterbi

__all__ = ["AnalogHMM", "Catalog", "forward_backward", "viterbi"]
