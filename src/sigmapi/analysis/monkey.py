# Over 500 lines: one protocol (the fixations, the admission, the statistics the studies used:
# the ANOVA with its beta function, the planar fits, the displacement index), read as one.
"""The map probed as the monkey studies of gain fields probed parietal cortex.

The animal fixates each point of a grid of eye positions (:data:`EYE_GRID` along every gaze
axis; Andersen et al. 1990 mapped gain fields at 9 eye positions, 3 x 3, and Avillac et al.
2005 used 3 fixation targets) while a stimulus
is flashed at each point of a grid of retinal positions (:data:`N_RETINA` per retinal axis).
Each unit's response to every (fixation, stimulus) condition is recorded
(:func:`fixation_protocol`) and read three ways:

- **admission**: a unit enters the statistics where its receptive field is mapped at every
  fixation it needs: at a fixation the field counts where the unit's best response there is at
  least :data:`RESPONDS` of its best at any fixation and no probe of
  its half-maximum region (within
  :data:`~sigmapi.analysis.physiology.CENTRE_RADIUS` of the peak) lies on the grid's edge;
  a unit is admitted where, along every retinal axis, the fields counted at fixations of at
  least 3 distinct eye positions along the gaze axis that moves them. A recording keeps the
  neurons whose field it could map within the screen; the units left out (most of them at
  the map's edge, whose fields leave the retina as the eyes move) are counted by reason, and
  their indices are reported too (``all_units``);
- **reference-frame index**: the least-squares slope of the receptive-field centre against
  the eye position, over the fixations where the field counted, divided by the slope of a
  body-centred field (0 eye-centred, 1 body-centred), the mean over retinal axes. Duhamel
  et al. 1997 and Avillac et al. 2005 measured the shift of a field between fixations
  against the eye's displacement; this protocol takes the field's centre (the centre of mass
  of its half-maximum region). Avillac et al. aligned the fields by cross-correlation: that
  is ``displacement_index`` (:func:`displacement_index`), on the admitted units;
- **gain modulation** (Andersen et al. 1985; 1990): the stimulus held at the unit's best
  retinal position at the central fixation while the eyes move over the grid. The response
  is scaled to a firing rate (the unit's best response in the protocol at
  :data:`PEAK_RATE` Hz) and :data:`TRIALS` trials of Poisson spike counts in a
  :data:`WINDOW` s window are drawn per fixation; a one-way analysis of variance over the
  fixations at p < :data:`ALPHA` marks the unit gain-modulated (the test of those papers,
  an effect of eye position on the visual response). Also deterministic: the gain ratio
  ``(max - min) / (max + min)`` of the rates over the fixations and the planar fit
  ``rate ~ a + b . eye`` (R^2, Andersen et al. 1990's planar gain fields).

:data:`PUBLISHED` holds the numbers of those studies this project could check against a
source, each with the source and where it stands in the paper; the ones it could not check
say so (``verified: False``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.analysis.physiology import CENTRE_RADIUS, Recordable, _pairing, _slopes

__all__ = [
    "ALPHA",
    "EYE_GRID",
    "N_RETINA",
    "PEAK_RATE",
    "PUBLISHED",
    "TRIALS",
    "WINDOW",
    "anova_oneway",
    "displacement_index",
    "fixation_protocol",
    "monkey_protocol",
]

Array = NDArray[np.float64]

EYE_GRID = (0.3, 0.4, 0.5, 0.6, 0.7)
"""Eye positions along each gaze axis (fractions of the axis): 5 per axis, 25 fixations in
2-D. The monkey studies fixated 3 per axis (``(0.3, 0.5, 0.7)`` is their 3 x 3); on the
tuning seed (paper-2d seed 0) 5 admitted 26 units, 3 admitted 9 (the fields are large against
the retina, and a field that the grid's edge cuts at one eye position leaves that fixation
out)."""

N_RETINA = 21
"""Stimulus positions along each retinal axis (2-D: 21 x 21), 0 to 1."""

TRIALS = 8
"""Trials per fixation of the gain-modulation test."""

PEAK_RATE = 100.0
"""Firing rate (Hz) of a unit's best response in the protocol (the spiking deployment's peak
rate, docs/guide/neurons.md)."""

WINDOW = 0.5
"""Counting window (s) of a trial."""

ALPHA = 0.05
"""Significance level of the eye-position effect."""

RESPONDS = 0.25
"""A receptive field counts at a fixation where the unit's best response there is at least
this share of its best at any fixation (and the grid's edge does not cut it off)."""

PUBLISHED: tuple[dict[str, object], ...] = (
    {
        "study": "Andersen, Essick & Siegel 1985, Science 230:456-458",
        "area": "7a",
        "measure": "gain_modulated_share",
        "value": 0.57,
        "verified": False,
        "where": "text (figure not checked)",
        "note": "a share often quoted for this study; the abstract found says the "
        "activity of 'many of the neurons' is a gain factor of eye position times the "
        "receptive field; the number itself was not verified against the paper",
        "source": "https://doi.org/10.1126/science.4048942",
    },
    {
        "study": "Andersen, Bracewell, Barash, Gnadt & Fogassi 1990, J Neurosci 10:1176-1196",
        "area": "7a+LIP",
        "measure": "gain_modulated_share",
        "value": 0.5,
        "bound": "above",
        "verified": True,
        "where": "abstract: 'a majority of the cells showed significant effects of eye "
        "position'; gain fields mapped at 9 eye positions were 'usually planar or largely "
        "planar'",
        "note": "a majority: the share is above 0.5; the exact shares and R^2 values of the "
        "planar fits were not verified",
        "source": "https://discovery.researcher.life/article/eye-position-effects-on-visual-"
        "memory-and-saccaderelated-activity-in-areas-lip-and-7a-of-macaque/"
        "97f3356ed50930c6914522b5d5b9c687",
    },
    {
        "study": "Bremmer, Graf, Ben Hamed & Duhamel 1999, NeuroReport 10:873-878",
        "area": "VIP",
        "measure": "gain_modulated_share",
        "value": 40 / 74,
        "n": 74,
        "verified": True,
        "where": "abstract: 40 of 74 neurons revealed an eye-position effect (fixation task)",
        "source": "https://www.ncbi.nlm.nih.gov/pubmed/10208563",
    },
    {
        "study": "Bremmer, Ilg, Thiele, Distler & Hoffmann 1997, J Neurophysiol 77:944-961",
        "area": "MT / MST",
        "measure": "gain_modulated_share",
        "value": [0.61, 0.82],
        "verified": True,
        "where": "abstract: the response was modulated by eye position in 61 % of MT and "
        "82 % of MST neurons; two-dimensional regression planes fitted most neurons",
        "source": "https://homepage.ruhr-uni-bochum.de/klaus-peter.hoffmann/abstract/"
        "bremmer_jn1997.htm",
    },
    {
        "study": "Duhamel, Bremmer, Ben Hamed & Graf 1997, Nature 389:845-848",
        "area": "VIP",
        "measure": "reference_frame_index",
        "value": None,
        "verified": True,
        "where": "abstract: receptive fields 'organized along a continuum, from eye to head "
        "coordinates'",
        "note": "a distribution from 0 (eye-centred) to 1 (head-centred); its numbers were "
        "not verified",
        "source": "https://econpapers.repec.org/article/natnature/"
        "v_3a389_3ay_3a1997_3ai_3a6653_3ad_3a10.1038_5f39865.htm",
    },
    {
        "study": "Avillac, Deneve, Olivier, Pouget & Duhamel 2005, Nat Neurosci 8:941-949",
        "area": "VIP",
        "measure": "reference_frame_index",
        "value": None,
        "verified": True,
        "where": "abstract: visual receptive fields 'widely distributed between eye- to "
        "head-centered coordinates' (3 fixation targets); tactile fields head-centred",
        "note": "the displacement-index histogram (its median, shares and sign convention) "
        "was not verified",
        "source": "https://www.scilit.net/publications/167bfac559cf734b0b58308b3b065a12",
    },
    {
        "study": "Chen, DeAngelis & Angelaki 2014, J Neurophysiol 112:353-361",
        "area": "VIP",
        "measure": "reference_frame_index",
        "value": None,
        "verified": True,
        "where": "abstract: with large-field random-dot stimuli 'the vast majority of VIP "
        "neurons have eye-centered RFs', one head-centred, a small minority intermediate",
        "source": "https://pmc.ncbi.nlm.nih.gov/articles/PMC4064410",
    },
)
"""What the monkey studies report, as far as this project could check them: ``source`` is the
page the abstract was read on (the papers' figures and tables were not read)."""


def _grid(values: Sequence[float] | Array, d: int) -> Array:
    """Every combination of ``values`` over ``d`` axes ``(len(values)**d, d)``, C order."""
    axes = np.meshgrid(*([np.asarray(values, dtype=np.float64)] * d), indexing="ij")
    return np.stack([a.ravel() for a in axes], axis=1)


def fixation_protocol(
    model: Recordable, eye_grid: Sequence[float] = EYE_GRID, n_retina: int = N_RETINA
) -> dict[str, Array]:
    """Every unit's response to every condition: ``responses`` ``(E, P, K)`` for the
    fixations ``eyes`` ``(E, d)`` (``eye_grid`` along every gaze axis) and the stimuli
    ``stimuli`` ``(P, d)`` (``n_retina`` per retinal axis, 0 to 1)."""
    d = model.x_code.ndim
    grid = [_validate.number("eye_grid", v, 0.0, 1.0, fix="fractions of the gaze axis")
            for v in eye_grid]  # fmt: skip
    if len(set(grid)) < 3:
        raise _validate.fail(
            "eye_grid", "at least 3 distinct eye positions", list(eye_grid), "e.g. 0.3,0.5,0.7"
        )
    n = _validate.integer("n_retina", n_retina, 5, 101, fix=f"e.g. {N_RETINA}")
    eyes = _grid(sorted(set(grid)), d)
    stimuli = _grid(np.linspace(0.0, 1.0, n), d)
    x = model.x_code.encode(stimuli)
    resp = [model.respond(x, model.y_code.encode(np.repeat(e[None], len(stimuli), 0)))
            for e in eyes]  # fmt: skip
    return {"eyes": eyes, "stimuli": stimuli, "responses": np.asarray(resp, dtype=np.float64)}


def _betacf(a: float, b: float, x: float) -> float:
    """The continued fraction of the regularized incomplete beta function (Lentz's method,
    as in Numerical Recipes)."""
    tiny, c, d = 1e-300, 1.0, 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 301):
        for num in (
            m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m)),
            -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1)),
        ):
            d = 1.0 + num * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + num / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < 1e-14:
            break
    return h


def _beta_inc(a: float, b: float, x: float) -> float:
    """The regularized incomplete beta function ``I_x(a, b)``."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    lead = math.exp(
        math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x)
        + b * math.log1p(-x)
    )  # fmt: skip
    if x < (a + 1.0) / (a + b + 2.0):
        return lead * _betacf(a, b, x) / a
    return 1.0 - lead * _betacf(b, a, 1.0 - x) / b


def anova_oneway(groups: Array) -> tuple[float, float]:
    """One-way analysis of variance of ``groups`` ``(G, n)`` (G groups of n trials): the F
    statistic and its p-value (NaN, 1.0 where no trial varies)."""
    g, n = groups.shape
    means = groups.mean(axis=1)
    between = n * float(((means - groups.mean()) ** 2).sum()) / (g - 1)
    within = float(((groups - means[:, None]) ** 2).sum()) / (g * (n - 1))
    if within <= 0.0:
        return (math.inf, 0.0) if between > 0.0 else (math.nan, 1.0)
    f = between / within
    d1, d2 = g - 1.0, g * (n - 1.0)
    return f, _beta_inc(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f))


def _plane_r2(eyes: Array, h: Array) -> Array:
    """R^2 per unit of the least-squares plane ``h ~ a + b . eye`` (``h`` ``(E, K)``; NaN
    where ``h`` does not vary)."""
    design = np.hstack([eyes, np.ones((eyes.shape[0], 1))])
    beta, *_ = np.linalg.lstsq(design, h, rcond=None)
    sse = ((h - design @ beta) ** 2).sum(axis=0)
    sst = ((h - h.mean(axis=0)) ** 2).sum(axis=0)
    return np.where(sst > 0, 1.0 - sse / np.maximum(sst, 1e-300), np.nan)


def _fields(
    resp: Array, stimuli: Array, share: float
) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_]]:
    """Per fixation and unit: the receptive field's centre ``(E, K, d)`` (the centre of mass
    of the response above half its peak within :data:`CENTRE_RADIUS` of the peak, as
    :mod:`~sigmapi.analysis.physiology` measures it), whether the unit responds there
    ``(E, K)`` (its best response at least ``share`` of its best at any fixation) and whether
    the grid's edge cuts the half-maximum region off ``(E, K)`` (a probe of it on the edge of
    any retinal axis)."""
    peak = resp.max(axis=1)  # (E, K)
    best = stimuli[np.argmax(resp, axis=1)]  # (E, K, d)
    dist2 = np.sum((stimuli[None, :, None, :] - best[:, None, :, :]) ** 2, axis=3)
    above = np.maximum(resp - 0.5 * peak[:, None, :], 0.0) * (dist2 <= CENTRE_RADIUS**2)
    total = np.maximum(above.sum(axis=1), 1e-300)
    centre = np.einsum("epk,pd->ekd", above, stimuli) / total[:, :, None]
    edge = np.any((stimuli <= 0.0) | (stimuli >= 1.0), axis=1)  # (P,)
    cut = np.any((above > 0) & edge[None, :, None], axis=1)
    responds = (peak > 0) & (peak >= share * peak.max(axis=0, keepdims=True))
    return centre, responds, cut


def _best_shift(a: Array, b: Array, axis: int) -> Array:
    """Per unit (last axis): the shift ``s`` (in grid steps, refined by a parabola through the
    peak and its neighbours) that maximizes the correlation of ``a`` with ``b`` moved by ``s``
    along ``axis``: ``b[p + s] ~ a[p]``, over the overlap (at least half the grid)."""
    n = a.shape[axis]
    shifts = np.arange(-(n // 2), n // 2 + 1)
    corr = np.full((shifts.size, a.shape[-1]), -np.inf)
    for i, sh in enumerate(shifts):
        lo, hi = max(0, -sh), n - max(0, sh)  # the p with p + sh on the grid
        u = np.take(a, np.arange(lo, hi), axis=axis).reshape(-1, a.shape[-1])
        v = np.take(b, np.arange(lo + sh, hi + sh), axis=axis).reshape(-1, a.shape[-1])
        u, v = u - u.mean(axis=0), v - v.mean(axis=0)
        den = np.sqrt((u**2).sum(axis=0) * (v**2).sum(axis=0))
        corr[i] = np.where(den > 0, (u * v).sum(axis=0) / np.maximum(den, 1e-300), -np.inf)
    top = np.argmax(corr, axis=0)
    out = shifts[top].astype(np.float64)
    inner = (top > 0) & (top < shifts.size - 1)
    k = np.nonzero(inner)[0]
    c0, c1, c2 = corr[top[k] - 1, k], corr[top[k], k], corr[top[k] + 1, k]
    curv = c0 - 2 * c1 + c2
    ok = np.isfinite(curv) & (curv < 0)
    out[k[ok]] += 0.5 * (c0[ok] - c2[ok]) / curv[ok]
    return np.where(np.isfinite(corr.max(axis=0)), out, np.nan)


def displacement_index(
    resp: Array,
    stimuli: Array,
    eyes: Array,
    counts: NDArray[np.bool_],
    slopes: Array,
    pairing: list[int],
) -> Array:
    """Avillac et al. (2005)'s way to the reference-frame index ``(K,)``: for every two
    fixations that differ only along the gaze axis paired with retinal axis ``a`` and where
    the field counts at both (``counts`` ``(E, K)``), the shift that best aligns the two
    response maps by cross-correlation, over the eyes' displacement, over a body-centred
    field's shift (0 eye-centred, 1 body-centred); the median over such pairs, the mean over
    axes; NaN where an axis has no pair."""
    n_e, _, k = resp.shape
    d = stimuli.shape[1]
    n = len(np.unique(stimuli[:, 0]))
    step = 1.0 / (n - 1)
    maps = resp.reshape(n_e, *([n] * d), k)
    per_axis = np.full((d, k), np.nan)
    for a in range(d):
        g = pairing[a]
        others = [c for c in range(d) if c != g]
        found: list[list[float]] = [[] for _ in range(k)]
        for i in range(n_e):
            for j in range(i + 1, n_e):
                moved = eyes[j, g] - eyes[i, g]
                if moved == 0 or np.any(eyes[i, others] != eyes[j, others]):
                    continue
                both = counts[i] & counts[j]
                if not both.any():
                    continue
                shift = _best_shift(maps[i], maps[j], a) * step  # retinal units
                for u in np.nonzero(both & np.isfinite(shift))[0]:
                    found[u].append(float(shift[u] / (moved * slopes[a])))
        per_axis[a] = [np.median(f) if f else np.nan for f in found]
    every = np.all(np.isfinite(per_axis), axis=0)
    return np.where(every, np.nanmean(np.where(every, per_axis, 0.0), axis=0), np.nan)


def _shift_index(
    centre: Array, ok: NDArray[np.bool_], eyes: Array, slopes: Array, pairing: list[int]
) -> tuple[Array, Array]:
    """Per retinal axis and unit ``(d, K)``: the slope of the field's centre against the eye
    position along the paired gaze axis over the fixations in ``ok`` ``(E, K)``, over the
    body-centred slope (NaN where fewer than 3 distinct eye positions count); and the mean
    over axes ``(K,)``, NaN unless every axis was measured."""
    d, k = centre.shape[2], centre.shape[1]
    per_axis = np.full((d, k), np.nan)
    for a in range(d):
        e = eyes[:, pairing[a]]
        for u in range(k):
            m = ok[:, u]
            if np.unique(e[m]).size >= 3:
                per_axis[a, u] = np.polyfit(e[m], centre[m, u, a], 1)[0] / slopes[a]
    every = np.all(np.isfinite(per_axis), axis=0)
    return per_axis, np.where(every, np.nanmean(np.where(every, per_axis, 0.0), axis=0), np.nan)


def _plain(a: object) -> object:
    """NumPy to JSON: lists, NaN as None."""
    arr = np.asarray(a)
    if arr.dtype == bool:
        return arr.tolist()
    if arr.ndim == 0:
        v = float(arr)
        return v if math.isfinite(v) else None
    return [_plain(v) for v in arr]


def _summary(values: Array) -> dict[str, object]:
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {"n": 0, "median": None, "quartiles": [None, None]}
    return {
        "n": int(v.size),
        "median": float(np.median(v)),
        "quartiles": [float(np.quantile(v, 0.25)), float(np.quantile(v, 0.75))],
    }


def monkey_protocol(
    model: Recordable,
    eye_grid: Sequence[float] = EYE_GRID,
    n_retina: int = N_RETINA,
    slope: Sequence[float] | None = None,
    gaze_axes: Sequence[int] | None = None,
    seed: int = 0,
    responds: float = RESPONDS,
    recording: dict[str, Array] | None = None,
) -> dict[str, Any]:
    """The protocol of the gain-field studies (module docstring) on every unit of ``model``.

    ``slope`` and ``gaze_axes`` as :func:`~sigmapi.analysis.physiology.record` takes them;
    ``seed`` draws the trials' spike counts; ``responds``: :data:`RESPONDS`; ``recording``:
    a :func:`fixation_protocol` result to read instead of recording again. Returns per unit
    (lists, NaN as None): ``admitted``, ``reference_frame_index`` (admitted units),
    ``reference_frame_index_all`` (every unit, every fixation where it responds, the edge not
    checked), ``displacement_index`` (admitted units, by cross-correlation),
    ``preferred_z``, ``best_stimulus``, ``gain_p_value``, ``gain_modulated``, ``gain_ratio``,
    ``gain_r2``, ``gain_slope``; and the summaries: ``admitted`` ``left_out`` (by reason),
    ``gain_modulated_share``, ``gain_r2``, ``reference_frame_index`` (admitted, all units),
    and the ``published`` numbers to read them against.
    """
    d = model.x_code.ndim
    seed = _validate.integer("seed", seed, 0, 2**63 - 1, fix="e.g. 0")
    rec = recording if recording is not None else fixation_protocol(model, eye_grid, n_retina)
    eyes, stimuli, resp = rec["eyes"], rec["stimuli"], rec["responses"]
    n_e, _, k = resp.shape
    slopes, pairing = _slopes(model, slope), _pairing(model, gaze_axes)

    share = _validate.number("responds", responds, 0.0, 1.0, fix=f"e.g. {RESPONDS}")
    centre, strong, cut = _fields(resp, stimuli, share)
    per_axis, rfi = _shift_index(centre, strong & ~cut, eyes, slopes, pairing)
    admitted = np.isfinite(rfi)
    shifted = displacement_index(resp, stimuli, eyes, strong & ~cut, slopes, pairing)
    shifted = np.where(admitted, shifted, np.nan)
    # every unit admitted: every fixation where it responds at all, the edge not checked
    _, rfi_all = _shift_index(centre, resp.max(axis=1) > 0, eyes, slopes, pairing)

    mid = int(np.argmin(np.abs(eyes - 0.5).sum(axis=1)))  # the central fixation
    best = np.argmax(resp[mid], axis=0)  # (K,) the stimulus held in the field
    fixed = resp[:, best, np.arange(k)]  # (E, K)
    top = np.maximum(resp.max(axis=(0, 1)), 1e-300)
    rate = PEAK_RATE * np.maximum(fixed, 0.0) / top  # (E, K) Hz
    rng = np.random.default_rng(seed)
    counts = rng.poisson(rate[:, :, None] * WINDOW, size=(n_e, k, TRIALS)).astype(np.float64)
    p = np.array([anova_oneway(counts[:, u, :])[1] for u in range(k)])
    modulated = p < ALPHA
    hi, lo = rate.max(axis=0), rate.min(axis=0)
    ratio = np.where(hi + lo > 0, (hi - lo) / np.maximum(hi + lo, 1e-300), np.nan)
    r2 = _plane_r2(eyes, rate)
    design = np.hstack([eyes, np.ones((n_e, 1))])
    beta, *_ = np.linalg.lstsq(design, rate, rcond=None)
    gslope = np.linalg.norm(beta[:-1], axis=0) / np.maximum(rate.mean(axis=0), 1e-300)

    rel = model.sampler.relation
    pref_x = centre[mid]  # (K, d) the field's centre at the central fixation
    pref_z = np.asarray(rel.forward(pref_x, eyes[mid][None, :]), dtype=np.float64)

    # left out: the field moved off the grid or faded at too many fixations (too few eye
    # positions where it responds), or it responds there but the grid's edge cuts it off
    few = np.zeros(k, dtype=bool)
    for a in range(d):
        e = eyes[:, pairing[a]]
        few |= np.array([np.unique(e[strong[:, u]]).size < 3 for u in range(k)])
    reasons = {
        "responds_at_too_few_fixations": int((~admitted & few).sum()),
        "cut_by_the_grid_edge": int((~admitted & ~few).sum()),
    }
    return {
        "eye_grid": sorted({float(v) for v in eye_grid}),
        "n_retina": len(np.unique(stimuli[:, 0])),
        "fixations": eyes.tolist(),
        "trials_per_fixation": TRIALS,
        "peak_rate_hz": PEAK_RATE,
        "window_s": WINDOW,
        "alpha": ALPHA,
        "responds": share,
        "seed": seed,
        "test": (
            "one-way ANOVA over the fixations of Poisson spike counts at the unit's best "
            f"retinal position at the central fixation ({TRIALS} trials per fixation, "
            f"{WINDOW:g} s, best response = {PEAK_RATE:g} Hz), p < {ALPHA:g}"
        ),
        "per_unit": {
            "admitted": admitted.tolist(),
            "reference_frame_index": _plain(rfi),
            "reference_frame_index_per_axis": _plain(per_axis),
            "reference_frame_index_all": _plain(rfi_all),
            "displacement_index": _plain(shifted),
            "preferred_z": _plain(pref_z),
            "best_stimulus": _plain(stimuli[best]),
            "gain_p_value": _plain(p),
            "gain_modulated": modulated.tolist(),
            "gain_ratio": _plain(ratio),
            "gain_r2": _plain(r2),
            "gain_slope": _plain(gslope),
        },
        "units": int(k),
        "admitted": int(admitted.sum()),
        "admitted_share": float(admitted.mean()),
        "left_out": reasons,
        "gain_modulated_share": float(modulated[admitted].mean()) if admitted.any() else None,
        "gain_modulated_share_all": float(modulated.mean()),
        "gain_ratio": _summary(ratio[admitted]),
        "gain_r2": _summary(r2[admitted]),
        "gain_r2_modulated": _summary(r2[admitted & modulated]),
        "reference_frame_index": _summary(rfi),
        "reference_frame_index_all": _summary(rfi_all),
        "displacement_index": _summary(shifted),
        "reference_frame_index_left_out": _summary(rfi_all[~admitted]),
        "published": [dict(p) for p in PUBLISHED],
    }
