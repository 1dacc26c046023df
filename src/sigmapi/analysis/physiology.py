"""The map read as an electrophysiologist reads a brain area (docs/guide/neurons.md).

Every unit is "recorded" while the animal fixates one of several gaze directions and a probe
is flashed at positions across the retina:

- **tuning curves**: the unit's response over retinal position, one curve per fixed gaze
  (:func:`tuning_curves`);
- **reference-frame index** (Duhamel et al. 1997, area VIP): how far the receptive field
  moves on the retina when the gaze moves, divided by how far a body-centred receptive field
  would move: the least-squares slope of the receptive-field centre against the gaze, over
  the slope the relation gives at fixed z (``-1`` for ``z = (x + y) / 2``; a map learned
  from a world whose geometry is not the config's relation, such as the robot's, passes its
  own per gaze axis as ``slope``). 0: the field stays
  put on the retina (eye-centred); 1: it stays put in the body (body-centred). In 2-D the
  mean over the axes along which it could be measured (each swept with the other gaze axis
  at its middle), as a recording tests whichever fixation shifts leave the field mapped;
- **gain field** (Andersen et al. 1985, area 7a): the response at the unit's best retinal
  position at the middle gaze, as the gaze moves, fitted by a plane ``a + b . gaze``: its
  ``gain_r2`` and its slope ``gain_slope`` (``|b|`` over the mean response); and the
  ``peak_modulation`` ``(max - min) / (max + min)`` of the unit's best response at each gaze
  over the gazes where its field counts (:data:`VALID_SHARE`; a classic gain field: the
  field stays, its height changes; a body-centred unit: the field moves, its height stays).

Works on anything with ``respond(x, y)`` ``(B, K)``, ``x_code``, ``y_code``, ``map_shape``
and ``sampler`` (the relation): a loaded :class:`~sigmapi.SigmaPiSOM` model file, a map of
:mod:`sigmapi.neurons`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.codes import PopulationCode
from sigmapi.tasks import TwoViewSampler

__all__ = [
    "GAZES",
    "Recordable",
    "body_slope",
    "check_gaze_axes",
    "compare_distributions",
    "gain_fields",
    "record",
    "reference_frame_index",
    "tuning_curves",
]

Array = NDArray[np.float64]

GAZES = (0.2, 0.35, 0.5, 0.65, 0.8)
"""Gaze directions (fractions of the gaze axis) the units are recorded at."""

VALID_SHARE = 0.5
"""A receptive field counts at a gaze where the unit's best response there is at least this
share of its best response at any gaze, and the retina's edge does not cut it off."""

N_PROBE = 61
"""Probe positions along the swept retinal axis."""

COARSE = 15
"""Probe positions along each other retinal axis (2-D maps)."""

CENTRE_RADIUS = 0.1
"""Receptive-field centres are measured within this distance of the peak (fraction of the
retinal axis)."""


class Recordable(Protocol):
    """What :func:`record` reads of a map."""

    @property
    def x_code(self) -> PopulationCode: ...
    @property
    def y_code(self) -> PopulationCode: ...
    @property
    def map_shape(self) -> tuple[int, ...]: ...
    @property
    def sampler(self) -> TwoViewSampler: ...
    def respond(self, x: Array, y: Array) -> Array: ...


def body_slope(model: Recordable) -> float:
    """How far a body-centred receptive field moves on the retina per unit of gaze:
    ``d solve_x(z, y) / dy`` at the middle of the range (``-1`` for the paper's relation)."""
    rel = model.sampler.relation
    z = np.full(1, 0.5 * (rel.z_range[0] + rel.z_range[1]))
    h = 1e-3
    lo, hi = rel.solve_x(z, np.full(1, 0.5 - h)), rel.solve_x(z, np.full(1, 0.5 + h))
    return float((hi - lo)[0] / (2 * h))


def _retina(model: Recordable, axis: int, n: int) -> Array:
    """Probe positions on the retina ``(P, d)``, C order: ``n`` along ``axis``, and
    :data:`COARSE` along every other axis (where the field does not move)."""
    d = model.x_code.ndim
    counts = [n if a == axis else COARSE for a in range(d)]
    axes = np.meshgrid(*(np.linspace(0.0, 1.0, c) for c in counts), indexing="ij")
    return np.stack([a.ravel() for a in axes], axis=1)


def tuning_curves(
    model: Recordable,
    gazes: Sequence[float] = GAZES,
    axis: int = 0,
    n_probe: int | None = None,
    gaze_axis: int | None = None,
) -> tuple[Array, Array]:
    """Responses ``(G, P, K)`` to probes at ``P`` retinal positions ``(P, d)`` while the gaze
    sits at each of ``gazes`` along ``gaze_axis`` (default ``axis``; its other axes at 0.5);
    ``n_probe`` probes along the retinal ``axis`` (default :data:`N_PROBE`); returns
    ``(responses, positions)``."""
    d = model.x_code.ndim
    _validate.integer("axis", axis, 0, d - 1, fix=f"an axis of the retina grid (0..{d - 1})")
    moved = axis if gaze_axis is None else gaze_axis
    _validate.integer("gaze_axis", moved, 0, d - 1, fix=f"an axis of the gaze grid (0..{d - 1})")
    probes = _retina(model, axis, n_probe if n_probe is not None else N_PROBE)
    out = []
    for g in gazes:
        gaze = np.full((1, d), 0.5)
        gaze[0, moved] = g
        y = model.y_code.encode(np.repeat(gaze, probes.shape[0], axis=0))
        out.append(model.respond(model.x_code.encode(probes), y))
    return np.asarray(out), probes


def _centres(resp: Array, probes: Array, axis: int) -> tuple[Array, NDArray[np.bool_]]:
    """Receptive-field centre of each unit at each gaze ``(G, K, d)``: the centre of mass of
    the response above half its peak within :data:`CENTRE_RADIUS` of the peak (a second
    field elsewhere, or a tail, does not pull it); and where it counts ``(G, K)``: the unit's
    best response there at least :data:`VALID_SHARE` of its best at any gaze, and the field
    fully mapped along the swept ``axis``: no probe of that half-maximum region lies on the
    retina's edge along it (a field the edge cuts off has its centre of mass pulled inwards,
    and its shift measured short)."""
    peak = resp.max(axis=1)  # (G, K)
    best = probes[np.argmax(resp, axis=1)]  # (G, K, d)
    near = np.sum((probes[None, :, None, :] - best[:, None, :, :]) ** 2, axis=3) <= CENTRE_RADIUS**2
    above = np.maximum(resp - 0.5 * peak[:, None, :], 0.0) * near
    total = np.maximum(above.sum(axis=1), 1e-300)
    centre = np.einsum("gpk,pd->gkd", above, probes) / total[:, :, None]
    edge = (probes[:, axis] <= 0.0) | (probes[:, axis] >= 1.0)  # (P,)
    cut = np.any((above > 0) & edge[None, :, None], axis=1)  # (G, K)
    strong = peak >= VALID_SHARE * peak.max(axis=0, keepdims=True)
    return centre, ~cut & strong & (peak > 0)


def check_gaze_axes(gaze_axes: Sequence[int], d: int, fix: str) -> list[int]:
    """``gaze_axes`` as a list, if it is a permutation of the ``d`` gaze axes (one gaze axis
    per retinal axis); else a ConfigError naming it, with ``fix``."""
    vals = list(gaze_axes)
    ints = all(isinstance(v, int) and not isinstance(v, bool) for v in vals)
    if not ints or sorted(vals) != list(range(d)):
        raise _validate.fail(
            "gaze_axes", f"a permutation of the gaze axes 0..{d - 1}, one per retinal axis",
            vals, fix,
        )  # fmt: skip
    return vals


def _pairing(model: Recordable, gaze_axes: Sequence[int] | None) -> list[int]:
    """The gaze axis that moves the fields along each retinal axis: ``gaze_axes`` (a
    permutation of the axes) or the identity (the paper's relation pairs axis ``a`` of x with
    axis ``a`` of y; a body whose eye pan moves the image horizontally but comes second in its
    gaze code, like the iCub's, pairs them crosswise)."""
    d = model.x_code.ndim
    if gaze_axes is None or len(gaze_axes) == 0:
        return list(range(d))
    fix = "e.g. 1,0 where the second gaze axis moves the fields along the first retinal axis"
    return check_gaze_axes(gaze_axes, d, fix)


def _slopes(model: Recordable, slope: Sequence[float] | None) -> Array:
    """The body-centred slope per retinal axis (against the gaze axis that moves it): ``slope``
    (one value, or one per axis) or the relation's (:func:`body_slope`)."""
    d = model.x_code.ndim
    if slope is None or len(slope) == 0:
        return np.full(d, body_slope(model))
    vals = np.asarray([float(v) for v in slope], dtype=np.float64)
    if vals.size not in (1, d) or not np.all(np.isfinite(vals)) or np.any(vals == 0.0):
        raise _validate.fail(
            "body_slope",
            f"1 or {d} finite nonzero numbers (one per gaze axis)",
            list(slope),
            "e.g. -1 for z = (x + y) / 2",
        )
    return np.broadcast_to(vals, (d,)).copy()


def reference_frame_index(
    model: Recordable,
    gazes: Sequence[float] = GAZES,
    n_probe: int | None = None,
    slope: Sequence[float] | None = None,
    gaze_axes: Sequence[int] | None = None,
) -> dict[str, Any]:
    """Per unit: ``reference_frame_index`` (the mean over retinal axes of the receptive
    field's shift along it with the gaze axis that moves it (``gaze_axes``, default the same
    axis) over a body-centred field's; an axis counts where at least 3 gazes count, NaN where
    no axis does), ``per_axis`` (``(d, K)``) and ``valid_gazes`` (gazes that counted, per
    axis)."""
    d = model.x_code.ndim
    slopes = _slopes(model, slope)
    pairing = _pairing(model, gaze_axes)
    g = np.asarray(gazes, dtype=np.float64)
    per_axis, valid = [], []
    for axis in range(d):
        resp, probes = tuning_curves(model, gazes, axis, n_probe, pairing[axis])
        centre, ok = _centres(resp, probes, axis)
        idx = np.full(resp.shape[2], np.nan)
        for k in range(resp.shape[2]):
            m = ok[:, k]
            if m.sum() >= 3:
                idx[k] = np.polyfit(g[m], centre[m, k, axis], 1)[0] / slopes[axis]
        per_axis.append(idx)
        valid.append(ok.sum(axis=0))
    pa = np.asarray(per_axis)
    seen = np.isfinite(pa)
    rfi = np.where(
        seen.any(axis=0),
        np.where(seen, pa, 0.0).sum(axis=0) / np.maximum(seen.sum(axis=0), 1),
        np.nan,
    )
    return {
        "reference_frame_index": rfi,
        "per_axis": np.asarray(per_axis),
        "valid_gazes": np.asarray(valid),
    }


def gain_fields(
    model: Recordable,
    gazes: Sequence[float] = GAZES,
    n_probe: int | None = None,
    gaze_axes: Sequence[int] | None = None,
) -> dict[str, Array]:
    """Per unit ``(K,)``: ``gain_r2`` and ``gain_slope`` of the planar fit of the response at
    the unit's best retinal position at the middle gaze against the gaze (every gaze axis
    swept), and ``peak_modulation`` of its best response over the gazes (module docstring)."""
    d = model.x_code.ndim
    g = np.asarray(gazes, dtype=np.float64)
    rows, fixed, peaks = [], [], []
    mid = int(np.argmin(np.abs(g - 0.5)))
    pairing = _pairing(model, gaze_axes)
    for axis in range(d):
        resp, probes = tuning_curves(model, gazes, axis, n_probe, pairing[axis])
        best = np.argmax(resp[mid], axis=0)  # (K,) probe index at the middle gaze
        fixed.append(resp[:, best, np.arange(resp.shape[2])])  # (G, K)
        peaks.append(np.where(_centres(resp, probes, axis)[1], resp.max(axis=1), np.nan))
        gaze = np.full((g.size, d), 0.5)
        gaze[:, pairing[axis]] = g
        rows.append(gaze)
    design = np.hstack([np.vstack(rows), np.ones((g.size * d, 1))])
    h = np.vstack(fixed)  # (G d, K)
    beta, *_ = np.linalg.lstsq(design, h, rcond=None)
    resid = h - design @ beta
    sst = ((h - h.mean(axis=0)) ** 2).sum(axis=0)
    r2 = np.where(sst > 0, 1.0 - (resid**2).sum(axis=0) / np.maximum(sst, 1e-300), np.nan)
    mean = np.abs(h).mean(axis=0)
    slope = np.linalg.norm(beta[:-1], axis=0) / np.maximum(mean, 1e-300)
    pk = np.vstack(peaks)
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a unit with no field counted: NaN
        hi, lo = np.nanmax(pk, axis=0), np.nanmin(pk, axis=0)
    mod = (hi - lo) / np.maximum(np.abs(hi + lo), 1e-300)
    return {"gain_r2": r2, "gain_slope": slope, "peak_modulation": mod}


def record(
    model: Recordable,
    gazes: Sequence[float] = GAZES,
    n_probe: int | None = None,
    slope: Sequence[float] | None = None,
    gaze_axes: Sequence[int] | None = None,
) -> dict[str, Any]:
    """Every per-unit index of the module as lists (NaN as None), with their medians, the
    share of units with an index (``measured``) and the body-centred share (index >= 0.8);
    ``gaze_axes``: the gaze axis that moves the fields along each retinal axis."""
    rfi = reference_frame_index(model, gazes, n_probe, slope, gaze_axes)
    gf = gain_fields(model, gazes, n_probe, gaze_axes)
    idx = rfi["reference_frame_index"]
    ok = np.isfinite(idx)

    def plain(a: Array) -> list[float | None]:
        return [float(v) if np.isfinite(v) else None for v in np.asarray(a, dtype=float)]

    return {
        "reference_frame_index": plain(idx),
        "reference_frame_index_per_axis": [plain(a) for a in rfi["per_axis"]],
        "valid_gazes": np.asarray(rfi["valid_gazes"]).tolist(),
        **{k: plain(v) for k, v in gf.items()},
        "median_reference_frame_index": float(np.median(idx[ok])) if ok.any() else None,
        "measured": float(np.mean(ok)),
        "body_centred_share": float(np.mean(idx[ok] >= 0.8)) if ok.any() else None,
        "median_gain_r2": float(np.nanmedian(gf["gain_r2"])),
        "median_peak_modulation": float(np.nanmedian(gf["peak_modulation"])),
        "gazes": [float(v) for v in gazes],
        "body_slope": _slopes(model, slope).tolist(),
        "gaze_axes": _pairing(model, gaze_axes),
    }


def compare_distributions(a: Sequence[float | None], b: Sequence[float | None]) -> dict[str, Any]:
    """Two samples of an index (None/NaN left out): the two-sample Kolmogorov-Smirnov
    statistic ``ks`` and its asymptotic p-value (Stephens' approximation, as in Numerical
    Recipes), both medians and sizes."""
    xa = np.sort(np.asarray([v for v in a if v is not None and np.isfinite(v)], dtype=float))
    xb = np.sort(np.asarray([v for v in b if v is not None and np.isfinite(v)], dtype=float))
    if xa.size == 0 or xb.size == 0:
        return {
            "ks": None,
            "p_value": None,
            "n": [int(xa.size), int(xb.size)],
            "medians": [None, None],
        }
    grid = np.concatenate([xa, xb])
    cdf_a = np.searchsorted(xa, grid, side="right") / xa.size
    cdf_b = np.searchsorted(xb, grid, side="right") / xb.size
    ks = float(np.max(np.abs(cdf_a - cdf_b)))
    ne = xa.size * xb.size / (xa.size + xb.size)
    lam = (np.sqrt(ne) + 0.12 + 0.11 / np.sqrt(ne)) * ks
    j = np.arange(1, 101)
    p = float(np.clip(2.0 * np.sum((-1.0) ** (j - 1) * np.exp(-2.0 * (j * lam) ** 2)), 0.0, 1.0))
    return {
        "ks": ks,
        "p_value": p if lam > 0 else 1.0,
        "n": [int(xa.size), int(xb.size)],
        "medians": [float(np.median(xa)), float(np.median(xb))],
    }
