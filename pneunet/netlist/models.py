"""``.model`` cards and model names: the valve-card part of the elaboration."""
from __future__ import annotations

from ..common.errors import PneunetError
from .located import did_you_mean as _close, error_at as _err
from .syntax import Call, Pair, Word

#: valve .model card parameter -> slot
VALVE_CARD = {"Rf": "resistance", "pclose": "pressure_difference", "ptrans": "pressure_difference",
              "e": "dimensionless", "ain": "dimensionless", "aout": "dimensionless"}


class ModelCards:
    """Mixin of the elaboration builder: ``.model`` statements and ``VALVE(...)`` cards."""

    def _model(self, st, scope):
        if len(st.items) != 3 or not isinstance(st.items[1], Word):
            raise _err(".model needs a name and a card", st.span,
                       "e.g. .model myvalve VALVE(Rf=0.5 pclose=90kPa ptrans=150kPa e=2 ain=0.3 aout=0.7)")
        name, card = st.items[1].text, st.items[2]
        key = name.lower()
        if key in self.models:
            raise _err(f"model {name!r} defined twice", st.items[1],
                       f"first defined at {self.model_spans[key]}")
        if isinstance(card, Word):  # .model NAME axi  (an alias of a known valve)
            self.models[key] = self._lookup_model(card)
        elif isinstance(card, Call) and card.name.upper() == "VALVE":
            self.models[key] = self._valve_card(card, scope, name)
        elif isinstance(card, Call):
            raise _err(f"unknown model type {card.name!r}", card, "known: VALVE")
        else:
            raise _err(f"unexpected {card} in .model", card)
        self.model_spans[key] = st.span

    def _lookup_model(self, word: Word):
        from ..physics.valve_params import PAPER_VALVES

        key = word.text.lower()
        if key in self.models:
            return self.models[key]
        if key in PAPER_VALVES:
            return PAPER_VALVES[key]
        known = sorted(set(self.models) | set(PAPER_VALVES))
        raise _err(f"undefined valve model {word.text!r}", word,
                   _close(key, known) or "known: " + ", ".join(known))

    def _valve_card(self, card: Call, scope, name):
        from ..physics.valve_params import ValveParams

        values, extra, base = {}, {}, None
        canon = {k.lower(): k for k in VALVE_CARD}
        for arg in card.args:
            if isinstance(arg, Word) and base is None and not values:
                base = self._lookup_model(arg)
                continue
            if not isinstance(arg, Pair) or not isinstance(arg.key, Word):
                raise _err(f"VALVE(...) expects name=value, got {arg}", arg,
                           "e.g. VALVE(Rf=0.566 pclose=96.42kPa ...)")
            k = arg.key.text
            if k.lower() in canon:
                k = canon[k.lower()]
                values[k] = self._number(arg.value, VALVE_CARD[k], k, scope)
            elif "_" in k:
                extra[k] = self._scalar(arg.value, scope) if isinstance(arg.value, Word) else \
                    self._fail_value(arg)
            else:
                raise _err(f"unknown valve parameter {k!r}", arg.key,
                           _close(k, VALVE_CARD) or "known: " + ", ".join(VALVE_CARD) +
                           " and <effect>_<param> for effects")
        if base is not None:
            if not isinstance(base, ValveParams):
                raise _err("only a six-parameter valve can be the base of a VALVE card", card)
            values = {**base.as_dict(), **values}
        missing = [k for k in VALVE_CARD if k not in values]
        if missing:
            raise _err(f"valve model {name} misses {', '.join(missing)}", card,
                       "give all six (Rf pclose ptrans e ain aout) or start from a known valve: "
                       "VALVE(axi pclose=90kPa)")
        try:
            params = ValveParams(**values)
        except PneunetError as err:
            raise _err(f"valve model {name}: {err.message}", card, err.hint) from None
        if not extra:
            return params
        try:
            from ..physics.valve_effects import ValveModel
        except ImportError:
            raise _err(f"valve model {name}: effect parameters ({', '.join(extra)}) need "
                       "pneunet.physics.valve_effects.ValveModel, which this installation lacks", card) from None
        try:
            return ValveModel.from_card_params({**values, **extra})
        except PneunetError as err:
            raise _err(f"valve model {name}: {err.message}", card, err.hint) from None
