"""The paper's further analyses of a valve fit (secs. 5.1.1, 5.2, 5.3, 5.4).

* :func:`open_valve_resistance` — R_open of the fully open valve and r² (Fig. 6A)
* :func:`areas_vs_threshold` — effective areas vs the 1/R threshold (eq. 26, Fig. 8)
* :func:`mirror_table` — forward and backward parameters side by side (Table 1)
* :func:`seat_height_study` — parameters against seat height with linear trends (Fig. 9)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from ....common.errors import DataError
from ....physics.valve_params import PAPER_VALVES, ValveParams
from .data import PRESSURES, as_frame
from .fit import NAMES, inverse_resistance
from .separation import plane_to_params, smooth_svm


@dataclass
class OpenValveCheck:
    """Zero-intercept line √(p_in² − p_out²) = R_open·ṁ on fully open points."""

    R_open: float
    r2: float
    n: int
    mask: np.ndarray
    mdot: np.ndarray
    root: np.ndarray


def open_valve_resistance(data, *, ctrl_tolerance=10.0, sum_min=900.0) -> OpenValveCheck:
    """Sec. 5.1.1: R_open from the points with p_ctrl at atmosphere, p_in + p_out ≥ 900 kPa.

    "At atmosphere" means within ``ctrl_tolerance`` kPa of the lowest control
    pressure (the commanded value when the data has ``p_ctrl_cmd_kPa``).  The sum
    uses the measured pressures.  r² is 1 − SS_res/SS_tot about the mean.
    """
    frame, _ = as_frame(data)
    if "p_ctrl_cmd_kPa" in frame:
        ctrl = frame["p_ctrl_cmd_kPa"].to_numpy(float)
    else:
        ctrl = frame["p_ctrl_kPa"].to_numpy(float)
    p_in, p_out = frame["p_in_kPa"].to_numpy(float), frame["p_out_kPa"].to_numpy(float)
    mask = (ctrl <= ctrl.min() + ctrl_tolerance) & (p_in + p_out >= sum_min)
    if mask.sum() < 3:
        raise DataError(f"only {int(mask.sum())} fully open points (p_ctrl at its minimum, "
                        f"p_in + p_out ≥ {sum_min:g} kPa)",
                        hint="lower sum_min or measure at low control pressure")
    mdot = frame["mdot_mg_s"].to_numpy(float)[mask]
    root = np.sqrt(np.maximum(p_in[mask] ** 2 - p_out[mask] ** 2, 0.0))
    R = float(mdot @ root / (mdot @ mdot))
    ss_res = float(np.sum((root - R * mdot) ** 2))
    ss_tot = float(np.sum((root - root.mean()) ** 2))
    return OpenValveCheck(R_open=R, r2=1.0 - ss_res / ss_tot, n=int(mask.sum()), mask=mask,
                          mdot=mdot, root=root)


def areas_vs_threshold(fit, thresholds=None, *, n=12) -> pd.DataFrame:
    """Eq. 26 / Fig. 8: separate the points by 1/R > 1/R_sep for a range of thresholds.

    For each threshold (default: ``n`` values from 0.005 mg/(s·kPa) to 1/R_f) a
    linear SVM gives ã_in, ã_out and p̃_sep and its misclassified fraction; a second
    classifier keeps the fit's a_in, a_out and only adapts the offset (best
    p_sep by a scan) — the paper's red line in Fig. 8B.  The planes come from the
    smoothed-hinge solver (:func:`~pneunet.truth.valves.identify.separation.smooth_svm`, same problem to
    O(0.05) margin units): near 1/R_f the classes stop being separable and libsvm
    then needs tens of seconds per threshold.  Columns: ``inv_r_sep,
    ain, aout, psep, misclassified, misclassified_fixed, n_above``.
    """
    frame = fit.frame
    X = frame[list(PRESSURES)].to_numpy(float)
    inv_r = np.nan_to_num(inverse_resistance(frame), nan=0.0)
    if thresholds is None:
        thresholds = np.linspace(0.005, 1.0 / fit.params.Rf, n)
    dp = fit.delta_p()
    rows = []
    for thr in np.asarray(thresholds, float):
        y = np.where(inv_r > thr, 1, -1)
        row = {"inv_r_sep": thr, "n_above": int((y > 0).sum())}
        if 0 < row["n_above"] < len(y):
            try:
                w, b = smooth_svm(X, y, fit.C, start=fit.plane)
                ain, aout, psep = plane_to_params(w, b)
                wrong = np.sign(X @ w + b) != y
                row.update(ain=ain, aout=aout, psep=psep, misclassified=float(wrong.mean()))
            except DataError:
                row.update(ain=np.nan, aout=np.nan, psep=np.nan, misclassified=np.nan)
            row["misclassified_fixed"] = _best_offset_error(dp, y)
        else:
            row.update(ain=np.nan, aout=np.nan, psep=np.nan, misclassified=np.nan,
                       misclassified_fixed=np.nan)
        rows.append(row)
    return pd.DataFrame(rows)


def _best_offset_error(dp, y):
    """Smallest misclassified fraction of the rule Δp > p over all offsets p."""
    order = np.argsort(dp)
    ys = y[order]
    # predicting closed for the first k sorted points, open for the rest
    closed_wrong = np.concatenate([[0], np.cumsum(ys > 0)])       # opens called closed
    open_wrong = np.concatenate([[0], np.cumsum((ys < 0)[::-1])])[::-1]  # closed called open
    return float(np.min(closed_wrong + open_wrong) / len(y))


def mirror_table(forward, backward) -> pd.DataFrame:
    """Table 1: forward and backward fits of a mirror valve with the paper's values."""
    rows = []
    for k in NAMES:
        rows.append({"param": k,
                     "forward": getattr(forward.params, k),
                     "forward_stderr": forward.stderr[k],
                     "backward": getattr(backward.params, k),
                     "backward_stderr": backward.stderr[k],
                     "paper_forward": getattr(PAPER_VALVES["mirror_forward"], k),
                     "paper_backward": getattr(PAPER_VALVES["mirror_backward"], k)})
    table = pd.DataFrame(rows).set_index("param")
    table["difference_sigma"] = (table["forward"] - table["backward"]) / np.hypot(
        table["forward_stderr"], table["backward_stderr"])
    return table


def seat_height_study(fits, h_seat) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Fig. 9: the six parameters of several valves against seat height, with trends.

    ``fits``: ValveFit or ValveParams per valve; ``h_seat``: their measured seat
    heights (mm).  Returns ``(values, trends)``: one row per valve (with standard
    errors where known), and per parameter the least-squares line with intercept
    (``slope, slope_stderr, intercept, r2``).
    """
    h = np.asarray(h_seat, float)
    if len(h) != len(fits) or len(h) < 3:
        raise DataError(f"need one seat height per valve and at least 3 valves, got "
                        f"{len(fits)} fits and {len(h)} heights")
    rows = []
    for fit, height in zip(fits, h):
        params = fit if isinstance(fit, ValveParams) else fit.params
        row = {"h_seat_mm": height, **params.as_dict()}
        if not isinstance(fit, ValveParams):
            row.update({f"{k}_stderr": fit.stderr[k] for k in NAMES})
        rows.append(row)
    values = pd.DataFrame(rows)
    trends = []
    for k in NAMES:
        v = values[k].to_numpy(float)
        A = np.column_stack([h, np.ones_like(h)])
        coef, *_ = np.linalg.lstsq(A, v, rcond=None)
        resid = v - A @ coef
        dof = max(len(h) - 2, 1)
        s2 = resid @ resid / dof
        cov = s2 * np.linalg.inv(A.T @ A)
        ss_tot = np.sum((v - v.mean()) ** 2)
        trends.append({"param": k, "slope": coef[0], "slope_stderr": np.sqrt(cov[0, 0]),
                       "intercept": coef[1],
                       "r2": 1.0 - resid @ resid / ss_tot if ss_tot > 0 else 1.0})
    return values, pd.DataFrame(trends).set_index("param")


def synthetic_seat_series(h_seat=None, *, seed=0) -> list[tuple[float, ValveParams]]:
    """Illustrative valves for a seat-height study (NOT the paper's Fig. 9 data).

    The paper gives no numbers for Fig. 9, only that p_close and p_trans depend on
    the seat height while a_in, a_out, R_f and e barely change.  These made-up
    linear trends (p_close +80 kPa/mm, p_trans +60 kPa/mm through the axi valve at
    0.6 mm, small scatter) let the study and its plot be exercised on bench data.
    """
    rng = np.random.default_rng(seed)
    if h_seat is None:
        h_seat = np.repeat(np.arange(0.1, 0.8, 0.1), 2)
    base = PAPER_VALVES["axi_0p6mm"]
    out = []
    for h in np.asarray(h_seat, float):
        dh = h - 0.6
        out.append((float(h), ValveParams(
            Rf=base.Rf * (1 + 0.02 * rng.standard_normal()),
            pclose=base.pclose + 80.0 * dh + 2.0 * rng.standard_normal(),
            ptrans=base.ptrans + 60.0 * dh + 3.0 * rng.standard_normal(),
            e=base.e + 0.05 * rng.standard_normal(),
            ain=base.ain + 0.01 * rng.standard_normal(),
            aout=base.aout + 0.01 * rng.standard_normal())))
    return out
