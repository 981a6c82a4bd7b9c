"""Plain-text report of a :class:`~pneunet.truth.circuits.diagnosis.TraceDiagnosis`."""
from __future__ import annotations

import math

VERDICT_TEXT = {
    "adequate": "ADEQUATE: the base model is at the noise floor; nothing is missing that "
                "the recording can show",
    "explained": "EXPLAINED: the accepted effect(s) bring the held-out error to the noise floor",
    "unexplained": "UNEXPLAINED: structure above the noise floor that no candidate removes",
}


def format_report(d) -> str:
    L = ["[[Diagnosis: circuit vs recording]]"]
    L.append(f"    fitted on     = {d.train_window[0]:g} … {d.train_window[1]:.4g} s, held out "
             f"{d.test_window[0]:.4g} … {d.test_window[1]:.4g} s"
             + (f", one sample in {d.fitted_every} (see the notes)" if d.fitted_every > 1
                else ""))
    if d.final.start_state is not None:
        L.append(f"    start state   = {d.final.start_state.describe()}")
    L.append(f"    noise floor   = {d.noise_floor:.3g} {d.unit} (estimated from the data: "
             f"{d.noise['method']})")
    L.append(f"    verdict       = {VERDICT_TEXT[d.verdict]}")
    L.append(f"    accepted      = {', '.join(d.accepted) or '(none)'}")
    L.append(f"[[Error waterfall]] (held-out rms, {d.unit})")
    L.append(d.waterfall.table())
    L.append("[[Candidates]] (ranked by held-out error)")
    L.append(f"    {'effect':<26}{'held-out':>10}{'× floor':>9}  parameters (95 % CI)")
    for r in d.ranking:
        if r["held_out_rms"] is None:
            L.append(f"    {r['effect']:<26}{'-':>10}{'':>9}  {r['note']}")
            continue
        par = ", ".join(f"{k}={v:.4g} [{r['ci'][k][0]:.3g}, {r['ci'][k][1]:.3g}]"
                        for k, v in r["values"].items())
        L.append(f"    {r['effect']:<26}{r['held_out_rms']:10.3g}{r['ratio_to_floor']:9.2f}  {par}")
    if len(d.signals) > 1 or d.unit != "kPa":
        L.append("[[Per signal]] (held-out rms in each signal's unit)")
        L.append(f"    {'signal':<22}{'floor':>10}{'base':>10}{'final':>10}{'× floor':>9}")
        for s, row in d.signals.items():
            L.append(f"    {s:<22}{row['noise_floor']:10.3g}{row['base_held_out']:10.3g}"
                     f"{row['held_out']:10.3g}{row['ratio_to_floor']:9.2f}  {row['unit']:<4}"
                     + ("" if row["at_floor"] else " above its floor"))
    if d.where:
        L.append("[[Where the model fails]]")
        L += [f"    - {w}" for w in d.where]
    t = d.timing
    if t:
        L.append(f"[[Time]] base fit {t.get('base_fit_s', math.nan):.1f} s, whole diagnosis "
                 f"{t.get('total_s', math.nan):.1f} s, {t.get('simulations', 0)} simulations")
    L += [f"note: {n}" for n in d.notes]
    return "\n".join(L)
