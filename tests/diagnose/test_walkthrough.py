"""Done-when 3: the user-defined-effect walkthrough of docs/diagnose.md runs as written."""
import re
from pathlib import Path

from pneunet.physics.valve_effects import available_effects, unregister_effect

DOC = Path(__file__).resolve().parents[2] / "docs" / "diagnose.md"


def test_walkthrough_runs_and_names_the_user_effect(tmp_path, monkeypatch, capsys):
    text = DOC.read_text(encoding="utf-8")
    section = text.split("<!-- walkthrough:start -->")[1].split("<!-- walkthrough:end -->")[0]
    code = "\n".join(re.findall(r"```python\n(.*?)```", section, flags=re.S))
    assert "register_effect" in code and "diagnose(" in code
    monkeypatch.chdir(tmp_path)  # the walkthrough writes its figures relative to cwd
    ns = {}
    try:
        exec(compile(code, str(DOC), "exec"), ns)
        first, second = ns["first"], ns["second"]
        assert first.verdict == "unexplained" and first.accepted == []
        assert [w["feature"] for w in first.where][0] in ("p_ctrl", "dp")
        assert "control-area" in available_effects()
        assert second.accepted == ["control-area"]
        assert second.verdict == "explained"
        c = second.final.fit.effect_params()["control-area"]["c"]
        assert abs(c["value"] - 2.5e-4) < 0.15 * 2.5e-4
        assert second.final.cv_rmse < 0.75 * second.baseline.cv_rmse
        table = capsys.readouterr().out
        assert "| + control-area |" in table and "noise floor" in table
        assert (tmp_path / "docs/figures/diagnose/walkthrough/waterfall.png").stat().st_size > 0
        assert "control_area_c=" in second.model_card()
    finally:
        unregister_effect("control-area")
