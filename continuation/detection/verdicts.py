"""The certifier's verdict on one interval [a, b] between neighbouring samples of a step.

A verdict says what the interval still needs (collisions.py acts on it):
  events  eigenvalues whose status goes 0 -> +-1 (births, paired at b) or +-1 -> 0 (deaths,
          paired at a), paired by conjugacy and continuity of the pair's mean
          (tracking.conjugate_pairing): the interval holds collisions to locate;
  split   a status change the events do not explain, or a pair that could collide and is not
          certified: a new sample is needed, at split_at; for the fast detection also the
          labels in trouble, the only ones a partial sample there must compute;
  clean   neither.
Fast detection (samples with slopes): every pair that could collide is certified by the cubic
Hermite model of its discriminant (certify.worst_uncertified_pair), the labels by their slopes
(certify.inconsistent_labels), and each event pair must change sign once and stay apart from
the other eigenvalues and event pairs (certify.event_pair_clearance, event_pairs_apart), so the
locator can start from its model. Exhaustive detection (version 0.1): the quadratic through a
third sample with the status of the adjacent end (certify.curvature_too_large) and the motion
of every real eigenvalue against its gap (certify.outruns_gaps).

With a spectral window, the labels beyond its certified band at both ends whose cubic model
stays beyond it in between (beyond_band) are left out of the events and the certificates:
their collisions lie outside the window. Their status changes need no explaining either
(explained_within_band), where all labels' cannot be.

Pure functions of samples (samples.Sample) and the tolerances they are given: rho is the
certification margin, doubt the weight of a model's cubic term (certify.py); the resolution
floor of a pair's discriminant is 4 thr^2 and of a label's defect 2 thr, thr the larger status
threshold of the two ends (below it nothing can be resolved).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from typing import Optional

import numpy as np

from diskfriction.continuation.detection import certify
from diskfriction.continuation.detection.labels import known
from diskfriction.continuation.detection.samples import Sample, pair_coupling
from diskfriction.continuation.stepping.segment import Segment
from diskfriction.continuation.spectra.tracking import Kind, conjugate_pairing

Array = np.ndarray

SPLIT_OFF_ENDS = 0.125
"""A fast split is placed at least this fraction of the interval away from either end (the
worst pair's model minimum may sit at an end: a sample there would teach nothing new)."""
CROSSING_OFF_ENDS = 1e-6
"""A split at the root of a crossing real pair's gap model (certify._crossing) keeps only this
far off the interval's ends: the model is transversal, so its root is where the pair resolves,
and a sample there certifies both sides in one step."""


class VerdictKind(StrEnum):
    """What an interval still needs (module docstring)."""

    CLEAN = "clean"
    SPLIT = "split"
    EVENTS = "events"


@dataclass(frozen=True)
class Verdict:
    """kind: a VerdictKind; events [(i, j, tracking.Kind)]; consistent:
    whether the events explain the status change; split_at: where to sample next (in s);
    labels: for a split of the fast detection, the mask of labels in trouble (the only ones a
    partial sample there needs), or None if the next sample must be a full spectrum."""

    kind: VerdictKind
    events: list
    consistent: bool
    split_at: float = math.nan
    labels: Optional[Array] = None


def active_labels(a: Sample, b: Sample) -> Array:
    """The labels known at both ends (all, between full samples)."""
    return known(a) & known(b)


def status_events(a: Sample, b: Sample, active: Optional[Array] = None):
    """Births (0 -> +-1, paired at b) and deaths (+-1 -> 0, paired at a) on [a, b], and
    whether the status change is fully explained by them. Modes excluded at either end, and
    labels outside `active` (default all), never take part."""
    tracked = ~(a.excluded | b.excluded) & (True if active is None else active)
    sa, sb = np.where(tracked, a.status, 0), np.where(tracked, b.status, 0)
    if np.array_equal(sa, sb):
        return [], True
    born, died = (sa == 0) & (sb != 0), (sa != 0) & (sb == 0)
    bu, bl = np.flatnonzero(born & (sb > 0)), np.flatnonzero(born & (sb < 0))
    du, dl = np.flatnonzero(died & (sa > 0)), np.flatnonzero(died & (sa < 0))
    events = [(i, j, Kind.BIRTH) for i, j in conjugate_pairing(b.eigvals, bu, bl, other=a.eigvals)]
    events += [(i, j, Kind.DEATH) for i, j in conjugate_pairing(a.eigvals, du, dl, other=b.eigvals)]
    consistent = bu.size == bl.size and du.size == dl.size and not np.any(sa * sb < 0)
    return events, consistent


def band_side(sample: Sample) -> Array:
    """+1 / -1 where a label's Re lambda lies above / below the sample's certified band
    (Sample.band, a spectral window's), 0 inside it, where unknown (nan) or without a band."""
    side = np.zeros(sample.eigvals.size, int)
    if sample.band is not None:
        with np.errstate(invalid="ignore"):
            side[sample.eigvals.real > sample.band[1]] = 1
            side[sample.eigvals.real < sample.band[0]] = -1
    return side


def beyond_band(a: Sample, b: Sample, d_a: Array, d_b: Array, doubt: float) -> Array:
    """Labels beyond the certified band on the same side at both ends of [a, b] whose cubic
    Hermite model of Re lambda (slopes d_a, d_b per unit of the interval) stays beyond it in
    between, by the doubt margin of the model's cubic term: no collision of theirs inside the
    interval lies in the window (spectra/window.py), so none is certified or located. A label
    whose model dips into the band takes part in the certificates."""
    side = band_side(a)
    beyond = (side != 0) & (side == band_side(b))
    for sign, edge in ((1, 1), (-1, 0)):  # above the band: Re lambda > hi; below: -Re lambda > -lo
        on = np.flatnonzero(beyond & (side == sign))
        if on.size:
            beyond[on] = certify.stays_above(sign * a.eigvals[on].real, sign * b.eigvals[on].real,
                                             sign * d_a[on].real, sign * d_b[on].real,
                                             sign * a.band[edge], doubt)
    return beyond


def judge_fast(a: Sample, b: Sample, segment: Segment, rho: float, doubt: float) -> Verdict:
    """The fast detection's verdict on [a, b] (module docstring; the samples carry slopes). The
    status change must be explained by births and deaths of all active labels, or, with a
    window, of those within its certified band (explained_within_band); the events and
    certificates leave out the labels beyond a window's certified band (beyond_band)."""
    active = active_labels(a, b)
    events, consistent = status_events(a, b, active)
    if not consistent and a.band is None:
        return Verdict(VerdictKind.SPLIT, events, False, 0.5 * (a.s + b.s))
    d_a, d_b = scaled_slopes(a, b, segment)
    beyond = beyond_band(a, b, d_a, d_b, doubt)
    if not consistent and beyond.any():
        events, consistent = explained_within_band(a, b, active, beyond, events)
    if not consistent:
        return Verdict(VerdictKind.SPLIT, events, False, 0.5 * (a.s + b.s))
    if beyond.any():
        events = [(i, j, kind) for i, j, kind in events if not (beyond[i] or beyond[j])]
        active = active & ~beyond
    split = hermite_split(a, b, d_a, d_b, events, active, rho, doubt)
    if split is not None:
        t_split, labels = split
        return Verdict(VerdictKind.SPLIT, events, True, a.s + t_split * (b.s - a.s), labels)
    return _settled(events)


def explained_within_band(a: Sample, b: Sample, active: Array, beyond: Array, events: list):
    """(events, consistent) of [a, b] on the active labels whose status change need not be
    explained by events: those beyond the window's certified band at both ends (beyond_band),
    and the partners of their events. Their collisions lie outside the window, where the
    relabelling of a quickly moving guard band is no concern: 256 sheared disks, 6.4e-11 in
    strain short of a contact opening, a complex pair at Re lambda = 9.06 died and another was
    born at 9.03 within one interval, past the band's edge at 8.83; the pairing could not
    explain it, the interval was too narrow to split, and the birth it held at 4.24, inside
    the window, was reported unresolved."""
    partners = np.zeros(active.size, bool)
    for i, j, _ in events:
        if beyond[i] or beyond[j]:
            partners[[i, j]] = True
    return status_events(a, b, active & ~beyond & ~partners)


def judge_exhaustive(a: Sample, b: Sample, stencil: Optional[Sample], rho: float) -> Verdict:
    """The exhaustive detection's verdict on [a, b] (module docstring) with the third sample
    `stencil` (None: none available, the interval splits)."""
    events, consistent = status_events(a, b, active_labels(a, b))
    if not consistent or stencil is None or uncertified(a, b, stencil, rho):
        return Verdict(VerdictKind.SPLIT, events, consistent, 0.5 * (a.s + b.s))
    return _settled(events)


def _settled(events: list) -> Verdict:
    """The verdict on a certified interval: events to locate, or clean."""
    return Verdict(VerdictKind.EVENTS if events else VerdictKind.CLEAN, events, True)


def scaled_slopes(a: Sample, b: Sample, segment: Segment) -> tuple[Array, Array]:
    """The eigenvalue slopes at a and b per unit of the interval's parameter t in [0, 1]."""
    h = b.s - a.s
    return a.slopes(segment) * h, b.slopes(segment) * h


def hermite_split(a: Sample, b: Sample, d_a: Array, d_b: Array, events: list, active: Array,
                  rho: float, doubt: float):
    """Fast: None if every candidate pair and every label is certified by the cubic models
    (slopes d_a, d_b per unit of the interval: scaled_slopes), else (where to split: t in
    [0, 1], where the first refusing test puts it, kept SPLIT_OFF_ENDS off the ends; the mask of
    labels in trouble, or None if the next sample must be full). The trouble is the union of
    every test's refusals, with the event pairs and conjugate partners: a partial split computes
    only those labels and rests on every other being certified on [a, b] (partial_splits.py;
    the first test's labels alone lost a pair of the chain of 400 disks:
    docs/notes/core-detection.md, "A split holds every label any test refuses")."""
    if _enters_past_guard(a, b).any():
        return 0.5, None
    real, upper, partner = _fast_candidates(a, b, active)
    thr = max(a.thr, b.thr)
    t_worst, pairs, crossing = certify.worst_uncertified_pair(a.eigvals, b.eigvals, d_a, d_b, real,
                                                              upper, partner, rho, 4.0 * thr * thr,
                                                              doubt, lambda I, J: _decoupled(a, b, I, J))
    labels = ~(a.excluded | b.excluded) & (a.status == b.status) & active
    wrong = labels & certify.inconsistent_labels(a.eigvals, b.eigvals, d_a, d_b, a.gaps, b.gaps,
                                                 rho, 2.0 * thr)
    in_events = event_labels(events, active.size)
    refusals = []  # (where to split, labels in trouble, how far off the ends), in the tests' order
    if not math.isnan(t_worst):
        refusals.append((t_worst, pairs, CROSSING_OFF_ENDS if crossing else SPLIT_OFF_ENDS))
    if wrong.any():
        refusals.append((0.5, _near_path(a, b, wrong), SPLIT_OFF_ENDS))
    others = np.flatnonzero((a.status == b.status) & (a.status >= 0) & ~a.excluded & ~b.excluded & active)
    models = [event_model(a, b, i, j, d_a, d_b) for i, j, _ in events]
    for (i, j, _), (m, D) in zip(events, models):  # one sign change of D per event, each pair apart
        if len(certify.cubic_roots_in_unit(D)) != 1:
            refusals.append((0.5, in_events, SPLIT_OFF_ENDS))
        bad, t_min = certify.event_pair_clearance(m, D, a.eigvals[others], b.eigvals[others],
                                                  d_a[others], d_b[others], rho, 4.0 * thr * thr)
        if bad.any():  # an eigenvalue decoupled from both members may pass them
            k = others[bad]
            bad[bad] = ~(_decoupled(a, b, np.full(k.size, i), k) & _decoupled(a, b, np.full(k.size, j), k))
        if bad.any():
            near = np.zeros(active.size, bool)
            near[others[bad]] = True
            refusals.append((t_min[np.argmax(bad)], near, SPLIT_OFF_ENDS))
    if len(models) > 1:
        apart, t_apart = certify.event_pairs_apart(models, rho, 4.0 * thr * thr)
        if not apart:
            refusals.append((t_apart, in_events, SPLIT_OFF_ENDS))
    if not refusals:
        return None
    t, _, off = refusals[0]
    return float(np.clip(t, off, 1.0 - off)), _with_partners(a, b, np.logical_or.reduce(
        [trouble for _, trouble, _ in refusals]) | in_events)


def _decoupled(a: Sample, b: Sample, I: Array, J: Array) -> Array:
    """Mask of the label pairs (I[k], J[k]) that are not conjugate partners and are decoupled
    at both ends (certify.decoupled on each end's pair_coupling, against the larger status
    threshold): modes that do not interact, which may pass through each other without a sample
    between. False where an end holds no vectors."""
    out = (a.status[I] * a.status[J] >= 0) & (b.status[I] * b.status[J] >= 0)
    thr = max(a.thr, b.thr)
    for smp in (a, b):
        if not out.any():
            break
        c = pair_coupling(smp, I[out], J[out])
        g, dg = smp.eigvals[I[out]] - smp.eigvals[J[out]], smp.dlam[I[out]] - smp.dlam[J[out]]
        with np.errstate(invalid="ignore"):
            out[out] = ~np.isnan(c) & certify.decoupled(g, dg, c, thr)
    return out


def event_model(a: Sample, b: Sample, i: int, j: int, d_a: Array, d_b: Array):
    """Cubic Hermite coefficients of the event pair's mean (Re) and signed discriminant D
    (D = (lambda_i - lambda_j)^2 real side, -(Im_i - Im_j)^2 complex side) over [a, b], from
    the slopes per unit t (scaled_slopes)."""
    def data(smp: Sample, d: Array):
        li, lj = smp.eigvals[i], smp.eigvals[j]
        mean, dmean = 0.5 * (li + lj).real, 0.5 * (d[i] + d[j]).real
        if smp.status[i] == 0:
            g = li.real - lj.real
            return mean, dmean, g * g, 2.0 * g * (d[i].real - d[j].real)
        im = li.imag - lj.imag
        return mean, dmean, -im * im, -2.0 * im * (d[i].imag - d[j].imag)

    (m0, dm0, y0, s0), (m1, dm1, y1, s1) = data(a, d_a), data(b, d_b)
    return (certify.hermite_coefficients(m0, m1, dm0, dm1),
            certify.hermite_coefficients(y0, y1, s0, s1))


def uncertified(a: Sample, b: Sample, c: Sample, rho: float) -> bool:
    """Exhaustive: some pair bends too much over [a, b] in the quadratic through c, or some
    real eigenvalue outruns its gap."""
    keep = (a.status == b.status) & ~a.excluded & ~b.excluded
    real = np.flatnonzero(keep & (a.status == 0))
    I, J = np.triu_indices(real.size, 1)
    I, J, upper = real[I], real[J], np.flatnonzero(keep & (a.status > 0))
    t_c = (c.s - a.s) / (b.s - a.s)
    floor = 4.0 * max(a.thr, b.thr) ** 2
    y = [np.concatenate([(smp.eigvals.real[I] - smp.eigvals.real[J]) ** 2, smp.eigvals.imag[upper] ** 2])
         for smp in (a, b, c)]
    return (certify.curvature_too_large(*y, t_c, rho, floor)
            or certify.outruns_gaps(a.eigvals, b.eigvals, real, rho, 2.0 * max(a.thr, b.thr)))


def event_labels(events: list, n: int) -> Array:
    """Mask of the labels of the event pairs [(i, j, kind), ...]."""
    mask = np.zeros(n, bool)
    mask[[k for i, j, _ in events for k in (i, j)]] = True
    return mask


def _fast_candidates(a: Sample, b: Sample, active: Array) -> tuple[Array, Array, Array]:
    """Labels whose pairs are certified over [a, b], among the active eigenvalues with
    unchanged status and no excluded mode: (real, upper, partner of each upper one); the pairs
    are two real ones, an upper complex one with a real one, and each upper one with its
    conjugate partner (certify.worst_uncertified_pair)."""
    keep = (a.status == b.status) & ~a.excluded & ~b.excluded & active
    real = np.flatnonzero(keep & (a.status == 0))
    upper = np.flatnonzero(keep & (a.status > 0))
    lower = np.flatnonzero(keep & (a.status < 0))
    partner = np.zeros(0, dtype=upper.dtype)
    if upper.size and lower.size:
        partner = lower[np.argmin(np.abs(a.eigvals[lower][None, :] - np.conj(a.eigvals[upper])[:, None]), axis=1)]
    return real, upper, partner


def events_in_trouble(a: Sample, b: Sample, events: list) -> Array:
    """The labels a partial sample splitting [a, b] for its events must compute: the event
    pairs' labels with their conjugate partners (the other pairs are certified on [a, b])."""
    return _with_partners(a, b, event_labels(events, a.eigvals.size))


def _with_partners(a: Sample, b: Sample, mask: Array) -> Array:
    """mask with the conjugate partner (at either end) of every complex member added: a
    partial sample's labels must include both members of a pair."""
    out = mask.copy()
    for smp in (a, b):
        lower = np.flatnonzero(known(smp) & (smp.status < 0))
        upper = np.flatnonzero(known(smp) & (smp.status > 0))
        for group, other in ((upper, lower), (lower, upper)):
            members = group[mask[group]]
            if members.size and other.size:
                distance = np.abs(smp.eigvals[other][None, :] - np.conj(smp.eigvals[members])[:, None])
                out[other[np.argmin(distance, axis=1)]] = True
    return out


def _near_path(a: Sample, b: Sample, wrong: Array) -> Array:
    """wrong with every label whose eigenvalue lies, at either end, within twice the
    displacement plus the gap of a wrong label from its own value there (the eigenvalues it may
    have been confused with)."""
    out = wrong.copy()
    for i in np.flatnonzero(wrong):
        reach = 2.0 * (abs(b.eigvals[i] - a.eigvals[i]) + max(a.gaps[i], b.gaps[i]))
        for smp in (a, b):
            with np.errstate(invalid="ignore"):
                out |= np.abs(smp.eigvals - smp.eigvals[i]) <= reach
    return out


def _enters_past_guard(a: Sample, b: Sample) -> Array:
    """Labels that join or leave the tracked set over [a, b] (excluded at one end only) without
    being in the guard band at the other end: an eigenvalue must cross the guard band to reach
    the window, so one found inside the window already entered within the interval unseen."""
    guard_a = np.zeros(a.excluded.size, bool) if a.guard is None else a.guard
    guard_b = np.zeros(b.excluded.size, bool) if b.guard is None else b.guard
    return (a.excluded & ~b.excluded & ~guard_b) | (b.excluded & ~a.excluded & ~guard_a)
