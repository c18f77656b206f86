"""Steps ending where a contact opens or forms: the square-root ends of a scan (root_ends.py).

A toy problem u = p whose 2 x 2 stability matrix [[m, 1], [d, m]] has the eigenvalues
m +- d^(1/2); d goes as the square root of the event function g near the event, as a Hertz
contact's stiffness goes as delta^(1/2)."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pytest

from diskfriction.continuation.detection import collisions
from diskfriction.continuation.stepping.arclength import ContinuationParams, continuation
from diskfriction.continuation.detection.collisions import DetectionParams
from diskfriction.continuation.problem import FunctionProblem
from diskfriction.continuation.detection.root_ends import root_slopes, scan_ends
from diskfriction.continuation.detection.samples import sample_at
from diskfriction.continuation.stepping.segment import Segment
from diskfriction.continuation.spectra.tracking import DEFAULT_REL_TOL

C, M, ALPHA, BETA = 0.5, 1.0, 1e-3, 1.0
P_DEATH = C - (ALPHA / BETA) ** 2
"""Opening at p = C: d = ALPHA - BETA (C - p)^(1/2) for p < C, ALPHA beyond, so the complex pair
dies at P_DEATH, 1e-6 before the event, and the eigenvalues' slopes diverge at the event."""


def _opening(p: float) -> float:
    return ALPHA - BETA * np.sqrt(max(C - p, 0.0))


def _forming(p: float) -> float:
    """d for a contact forming at p = C: smooth before, a square root after."""
    return -0.2 + 0.3 * (p - C) + np.sqrt(max(p - C, 0.0))


@dataclass(frozen=True)
class Toy(FunctionProblem):
    sign: float = 1.0  # +1: g = C - p (opening at C); -1: g = p - C (forming at C)
    roots: bool = True
    evaluations: list = None

    def event_functions(self, u, p):
        return np.array([self.sign * (C - p)])

    def root_events(self):
        return np.array([True]) if self.roots else None


def toy(d, sign=1.0, roots=True) -> Toy:
    count = []

    def A(u, p):
        count.append(p)
        return np.array([[M, 1.0], [d(p), M]])

    return Toy(G=lambda u, p: np.array([u[0] - p]), G_u=lambda u, p: np.eye(1), G_p=lambda u, p: np.array([-1.0]),
               A=A, sign=sign, roots=roots, evaluations=count)


def _params():
    return ContinuationParams(ds=0.05, ds_min=1e-10, ds_max=0.05, newton_tol=1e-14, p_min=-1.0, p_max=0.7)


def _branch(problem):
    detection = DetectionParams(tol_p=1e-11)
    return continuation(problem, np.array([0.3]), 0.3, _params(), detection, workers=0)


def test_segment_coordinate_is_the_square_root_map_and_its_inverse():
    problem = toy(_opening)
    x_a, x_b = np.array([0.3, 0.3]), np.array([0.5, 0.5])
    segment = Segment(problem, x_a, x_b, 1e-14, 8, root=0.999)
    for w in (0.0, 0.1, 0.5, 0.9, 0.999):
        s = segment.real(w)
        assert s == pytest.approx(0.999 * (1.0 - (1.0 - w) ** 2), abs=1e-15)
        assert segment.coordinate(s) == pytest.approx(w, abs=1e-12)
        h = 1e-7
        assert segment.ds_dw(w) == pytest.approx((segment.real(w + h) - segment.real(w - h)) / (2 * h), rel=1e-6)
    assert segment.real(1.0) == 1.0 and segment.coordinate(1.0) == 1.0
    # a point at w is the branch point at s(w): on the toy, p = 0.3 + 0.2 s
    assert segment.point(0.5)[1] == pytest.approx(0.3 + 0.2 * segment.real(0.5), abs=1e-13)
    plain = Segment(problem, x_a, x_b, 1e-14, 8)
    assert plain.real(0.37) == 0.37 and plain.coordinate(0.37) == 0.37 and plain.ds_dw(0.37) == 1.0


def test_root_slopes_are_the_derivative_in_the_coordinate():
    """At the opening end, d lambda / dw = -d lambda / dv with v = (1 - s / s_e)^(1/2):
    lambda = M +- (ALPHA - BETA (s_e dp/ds)^(1/2) v)^(1/2), so d lambda / dw = +-BETA (s_e
    dp/ds)^(1/2) / (2 ALPHA^(1/2)), finite where d lambda / ds is not."""
    problem = toy(_opening)
    p_a, p_b = 0.45, C + 1e-12  # x_b just past the event, as a step cut there ends
    x_a, x_b = np.array([p_a, p_a]), np.array([p_b, p_b])
    t = np.array([1.0, 1.0]) / np.sqrt(2.0)
    segment = Segment(problem, x_a, x_b, 1e-14, 8, t, t)
    end = sample_at(problem, 1.0, x_b, DEFAULT_REL_TOL, None, t, side=-1)
    rooted, root_end = scan_ends(problem, segment, end)
    s_e = (C - p_a) / (p_b - p_a)
    assert rooted.root == pytest.approx(s_e, abs=1e-12)
    assert root_end.root_end and root_end.s == end.s
    expected = BETA * np.sqrt(s_e * (p_b - p_a)) / (2.0 * np.sqrt(ALPHA))
    got = np.sort(root_end.slopes(rooted).real)
    assert got == pytest.approx([-expected, expected], rel=1e-4)
    # the one-sided difference along the tangent is large and far from it
    assert np.max(np.abs(end.slopes(segment))) > 10.0 * expected
    assert root_slopes(problem, rooted, end, (x_b - x_a) / 1.0).root_end


def test_forming_end_takes_its_slopes_on_the_steps_side():
    """Just past a forming contact the one-sided slopes into the step straddle the event and
    pick up part of d^(1/2)'s infinite slope (its whole at a difference step below the
    distance past the event: 3e3 to 8e4 times the step start's slopes at 256 disks); scan_ends takes
    them before it: d lambda / dp = +-0.3 /
    (2 (-d)^(1/2)) i for the complex pair of d = -0.2 + 0.3 (p - C)."""
    problem = toy(_forming, sign=-1.0)
    p_a, p_b = 0.45, C + 1e-13
    x_a, x_b = np.array([p_a, p_a]), np.array([p_b, p_b])
    t = np.array([1.0, 1.0]) / np.sqrt(2.0)
    segment = Segment(problem, x_a, x_b, 1e-14, 8, t, t)
    end = sample_at(problem, 1.0, x_b, DEFAULT_REL_TOL, None, t, side=-1)
    same, fixed = scan_ends(problem, segment, end)
    assert same is segment and not fixed.root_end
    expected = 0.3 / (2.0 * np.sqrt(0.2)) * (p_b - p_a)  # per unit s
    assert np.sort(np.abs(fixed.slopes(segment))) == pytest.approx([expected, expected], rel=1e-6)
    assert np.max(np.abs(end.slopes(segment))) > 1.2 * expected  # the square root's share


def _event_step_solves(monkeypatch, problem) -> tuple[list, int]:
    """The branch's collisions and the samples its scan of the step ending on the event took."""
    solves = []
    original = collisions.StepScan.run

    def run(self):
        found = original(self)
        if self.ends_at_event:
            solves.append(self.solves)
        return found

    monkeypatch.setattr(collisions.StepScan, "run", run)
    branch = _branch(problem)
    monkeypatch.setattr(collisions.StepScan, "run", original)
    assert len(solves) == 1
    return branch.collisions, solves[0]


def test_a_collision_next_to_an_opening_is_located_either_way(monkeypatch):
    """The death 1e-6 before the event: located to tol_p with the end treated as a square root
    and without (the model in w gives the locator a better start: 74 matrix evaluations in
    the whole run against 104)."""
    for roots in (True, False):
        found, _ = _event_step_solves(monkeypatch, toy(_opening, roots=roots))
        assert [c.kind.value for c in found] == ["death"] and found[0].resolved
        assert found[0].p == pytest.approx(P_DEATH, abs=1e-10)


def test_a_pair_falling_as_a_square_root_is_certified_without_splits(monkeypatch):
    """A complex pair whose Im^2 = 0.05 + (C - p)^(1/2) falls towards the opening, no collision:
    its discriminant is linear in w, so the step's models certify it from its ends; in s the
    end's slope is unbounded and the scan splits the step towards it."""
    falling = lambda p: -(0.05 + np.sqrt(max(C - p, 0.0)))  # noqa: E731
    rooted, plain = (_event_step_solves(monkeypatch, toy(falling, roots=roots)) for roots in (True, False))
    assert not rooted[0] and not plain[0]
    assert rooted[1] == 0 and plain[1] >= 2


def test_scans_without_slopes_keep_the_plain_coordinate(monkeypatch):
    """The exhaustive detection (no slopes) never addresses a step by w."""
    seen = []
    original = collisions.StepScan.__post_init__

    def record(self):
        seen.append(self.segment.root)
        original(self)

    monkeypatch.setattr(collisions.StepScan, "__post_init__", record)
    problem = toy(_opening)
    continuation(problem, np.array([0.3]), 0.3, _params(), DetectionParams(mode="exhaustive"), workers=0)
    assert seen and all(root is None for root in seen)
    seen.clear()
    _branch(replace(problem, evaluations=[]))
    assert any(root is not None for root in seen)
