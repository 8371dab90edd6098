"""Numerical stability at the extremes (docs/extremes.md).

The cases (parameters, expected physical answer or documented error, the
check) live in :mod:`cases.extremes`, shared with
``demos/studies/extremes_matrix.py`` (which writes docs/extremes.md); this module
asserts each of them and that the interior-point iterations stay roughly
constant across the matrix.  The column-collapse part of the matrix is in
tests/scenes/test_extremes_collapse.py.
"""

from __future__ import annotations

import pytest
from cases.extremes import DEFAULT, SLOW, result
from cases.framework import ENERGY_TOLERANCE


@pytest.mark.parametrize("case_", DEFAULT, ids=[c.name for c in DEFAULT])
def test_extreme_case(case_):
    out = result(case_.name)
    assert out.passed, f"{case_.name}: {out.outcome}; expected: {case_.expected}"
    # Beside the physical answer, the energy balance (cases.framework
    # EnergyBudget): no step creates energy.  nan: a documented error came
    # before the first step.
    assert not out.energy > ENERGY_TOLERANCE, f"{case_.name}: energy {out.energy:.3g}"


@pytest.mark.slow
@pytest.mark.parametrize("case_", SLOW, ids=[c.name for c in SLOW])
def test_extreme_case_slow(case_):
    out = result(case_.name)
    assert out.passed, f"{case_.name}: {out.outcome}; expected: {case_.expected}"
    # Beside the physical answer, the energy balance (cases.framework
    # EnergyBudget): no step creates energy.  nan: a documented error came
    # before the first step.
    assert not out.energy > ENERGY_TOLERANCE, f"{case_.name}: energy {out.energy:.3g}"


#: Largest ratio of the per-case peak IPM iterations (a) across the cases that
#: reach a collapse load (measured 14-24: Tresca 14, phi = 50 deg 24) and (b)
#: across every program with yield cones, including those whose cones stay
#: inactive (measured 6-24; 6 for the c = 1e12 footing).  Before the scaling
#: fixes in conic.py the same cases took 12-22 and 6-22.  Elastic programs are a
#: single KKT solve: 0 iterations.
ITERATION_FACTOR_YIELDING = 2.0
ITERATION_FACTOR_PLASTIC = 5.0


def test_iterations_stay_roughly_constant_across_the_matrix():
    outs = {c.name: result(c.name) for c in DEFAULT}
    peaks = {n: max(o.iterations) for n, o in outs.items() if o.plastic}
    yielding = {n: peaks[n] for n, o in outs.items() if o.yielding}
    assert len(peaks) >= 25 and len(yielding) >= 12
    assert max(yielding.values()) / min(yielding.values()) <= (
        ITERATION_FACTOR_YIELDING
    ), yielding
    assert min(peaks.values()) > 0
    assert max(peaks.values()) / min(peaks.values()) <= ITERATION_FACTOR_PLASTIC, peaks
    assert max(peaks.values()) <= 30, peaks
    elastic = [outs[c.name] for c in DEFAULT if c.scene == "elastic-column"]
    assert all(it == 0 for o in elastic for it in o.iterations)
