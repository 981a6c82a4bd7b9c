"""Flow laws of the paper, vectorised over numpy arrays, with their derivatives.

* quadrature (isothermal compressible) resistor, eq. 4: ṁ = √(p₁² − p₂²)/R
* six-parameter membrane valve, eqs. 13, 19 and 25

Units: kPa (absolute), mg/s, kPa·s/mg.

Zero-flow regularisation
------------------------
√d has an infinite slope at d = p₁² − p₂² = 0, which stalls Newton iterations.
Circuit simulation therefore uses the signed regularised root

    sr(d) = d / (d² + ε²)^(1/4)

which equals sign(d)·√|d| to a relative error below 1 % once |d| > 7ε and is
linear, with slope ε^(-1/2), for |d| ≪ ε.  ε (kPa², option ``flow_band``) is
documented in docs/numerics.md; the tests show results do not depend on it.
Identification uses the exact root (ε = 0).

Scalars
-------
Every law takes ``xp``, the namespace of ``sqrt``, ``maximum`` and ``minimum`` it
computes with: numpy (the default: arrays of any shape) or :class:`Scalar` (Python
floats).  On one instance numpy's per-call overhead is most of the cost (a valve's flow
and partials: ~23 µs on one-element arrays, ~1.3 µs on floats), so element families
with few instances evaluate them one by one with ``xp=Scalar``.  The scalar path needs
a positive band.
"""
from __future__ import annotations

import math

import numpy as np

DEFAULT_FLOW_BAND_KPA2 = 10.0
_TINY = 1e-300  # floor of a valve opening in the derivative of u^e


class Scalar:
    """numpy's names for the functions the laws use, on Python floats."""

    sqrt = staticmethod(math.sqrt)
    maximum = staticmethod(max)
    minimum = staticmethod(min)


def signed_root(d, band=0.0, derivative=True, xp=np):
    """sr(d) = d/(d²+ε²)^¼ and its derivative d sr/dd (exact √ when band == 0).

    The derivative is None when not asked for (the residual's fast path).
    """
    if xp is np:
        d = np.asarray(d, dtype=float)
    if band == 0.0:
        root = np.sqrt(np.abs(d))
        value = np.sign(d) * root
        if not derivative:
            return value, None
        with np.errstate(divide="ignore"):
            slope = np.where(root > 0, 0.5 / np.where(root > 0, root, 1.0), np.inf)
        return value, slope
    d2 = d * d
    s = d2 + band * band
    fourth_root = xp.sqrt(xp.sqrt(s))  # much faster than s ** 0.25
    value = d / fourth_root
    if not derivative:
        return value, None
    slope = (0.5 * d2 + band * band) / (s * fourth_root)
    return value, slope


def quadrature_flow(p_a, p_b, resistance, band=DEFAULT_FLOW_BAND_KPA2, partials=True, xp=np):
    """Mass flow a→b through a quadrature resistor and its partials.

    Returns ``(mdot, dmdot_dpa, dmdot_dpb)`` in mg/s and mg/(s·kPa); the
    partials are None when ``partials`` is False.
    """
    root, slope = signed_root(p_a * p_a - p_b * p_b, band, derivative=partials, xp=xp)
    mdot = root / resistance
    if not partials:
        return mdot, None, None
    slope = slope * (2.0 / resistance)
    return mdot, p_a * slope, -p_b * slope


def series_resistance(*resistances):
    """Quadrature resistors in series add in quadrature (eq. 5), kPa·s/mg."""
    return float(np.sqrt(np.sum(np.square(resistances))))


def valve_opening(delta_p, p_close, p_trans, xp=np):
    """Normalised opening u = (Δp − p_close)/(p_trans − p_close), 0 when closed."""
    return xp.maximum(delta_p - p_close, 0.0) / (p_trans - p_close)


def valve_conductance(delta_p, r_f, p_close, p_trans, e, derivative=True, xp=np):
    """Valve conductance 1/R = u^e / (R_f·√(1+u^(2e))) (eq. 19) and d(1/R)/dΔp.

    Written with u^e in the numerator so that it is exact and smooth as the valve
    closes (u → 0).  Returns ``(G, dG_ddp)`` in mg/(s·kPa) and mg/(s·kPa²);
    dG_ddp is None when ``derivative`` is False.
    """
    u = valve_opening(delta_p, p_close, p_trans, xp)
    ue = u ** e
    q = 1.0 + ue * ue
    root_q = xp.sqrt(q)
    g = ue / (r_f * root_q)
    if not derivative:
        return g, None
    # d(u^e)/du = e·u^e/u where open; 0 where closed (u^e = 0 over a positive floor)
    dg_du = e * ue / (xp.maximum(u, _TINY) * (r_f * q * root_q))
    return g, dg_du / (p_trans - p_close)


def valve_delta_p(p_in, p_out, p_ctrl, a_in, a_out, xp=np):
    """Equivalent membrane pressure difference Δp (eq. 13 / 25), kPa.

    a_in belongs to whichever of the two flow ports has the higher pressure.
    """
    return a_in * xp.maximum(p_in, p_out) + a_out * xp.minimum(p_in, p_out) - p_ctrl


def valve_flow(p_in, p_out, p_ctrl, Rf, pclose, ptrans, e, ain, aout, band=0.0):
    """Signed mass flow in→out of the six-parameter valve (eqs. 19, 25), mg/s.

    Parameter names follow :class:`pneunet.physics.valve_params.ValveParams`, so
    ``valve_flow(p_in, p_out, p_ctrl, **params.as_dict())`` works.  Exact law by
    default (``band=0``), as used for identification; circuits pass their flow
    band.  Arrays broadcast.
    """
    mdot, _ = valve_flow_and_partials(p_in, p_out, p_ctrl, Rf, pclose, ptrans, e, ain, aout,
                                      band, partials=False)
    return mdot


def valve_flow_and_partials(p_in, p_out, p_ctrl, Rf, pclose, ptrans, e, ain, aout,
                            band=DEFAULT_FLOW_BAND_KPA2, partials=True, xp=np):
    """Valve flow in→out and its partials with respect to (p_in, p_out, p_ctrl).

    Returns ``(mdot, (d_in, d_out, d_ctrl))``; the tuple is None when
    ``partials`` is False.
    """
    if xp is np:
        p_in, p_out, p_ctrl = (np.asarray(x, dtype=float) for x in (p_in, p_out, p_ctrl))
    dp = valve_delta_p(p_in, p_out, p_ctrl, ain, aout, xp)
    g, dg = valve_conductance(dp, Rf, pclose, ptrans, e, derivative=partials, xp=xp)
    root, slope = signed_root(p_in * p_in - p_out * p_out, band, derivative=partials, xp=xp)
    mdot = g * root
    if not partials:
        return mdot, None
    # ∂Δp/∂p_in is a_in where p_in is the higher port, else a_out (eq. 25)
    swap = (ain - aout) * (p_in >= p_out)
    dg_root = dg * root
    g_slope = 2.0 * g * slope
    d_in = dg_root * (aout + swap) + g_slope * p_in
    d_out = dg_root * (ain - swap) - g_slope * p_out
    return mdot, (d_in, d_out, -dg_root)
