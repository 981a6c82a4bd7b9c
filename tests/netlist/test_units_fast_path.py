"""Units converted without pint give exactly what pint gives."""
import pytest

from pneunet.netlist.values import SCALE, SCALE_LETTER_UNITS, pint_dimension_matches
from pneunet.physics.units import FAST_FACTORS, SLOTS, registry


@pytest.mark.parametrize("unit, slot", sorted(FAST_FACTORS))
def test_fast_factor_equals_pint_conversion(unit, slot):
    pint_factor = registry().Quantity(1.0, unit).to(SLOTS[slot]).magnitude
    assert FAST_FACTORS[unit, slot] == pytest.approx(pint_factor, rel=1e-12)


@pytest.mark.parametrize("slot", sorted(SLOTS))
def test_scale_letters_are_units_exactly_where_pint_says_so(slot):
    letters = [s for s in SCALE if s == s.lower()]
    fast = {x for x in letters if (x, slot) in SCALE_LETTER_UNITS}
    assert fast == {x for x in letters if pint_dimension_matches(x, slot)}


def test_a_netlist_with_common_units_does_not_build_the_pint_registry(tmp_path):
    """The registry costs ~0.5 s per process: common netlists must not need it."""
    import subprocess
    import sys

    deck = tmp_path / "fill.pn"
    deck.write_text("* fill\n.options ambient=96kPa\nPS s 596kPa\nR1 s t 0.566kPa*s/mg\n"
                    "V1 t 54.35mL\n.ic p(t)=200kPag\n.tran 1ms 0.2s\n")
    code = ("import sys; from pneunet.netlist import parse_file; parse_file(sys.argv[1]); "
            "from pneunet.physics.units import registry; print(registry.cache_info().currsize)")
    out = subprocess.run([sys.executable, "-c", code, str(deck)], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "0"
