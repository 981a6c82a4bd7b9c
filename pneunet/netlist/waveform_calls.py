"""Waveform calls of sources (``STEP``, ``PULSE``, ``PWL``, ``SIN``, ``DC``): the
waveform part of the elaboration."""
from __future__ import annotations

from ..common.errors import PneunetError
from . import plausible
from .datafiles import column, read_data_file
from .located import did_you_mean as _close, error_at as _err
from .syntax import Call, Pair, RawArgs, Word


class WaveformCalls:
    """Mixin of the elaboration builder: a source's waveform from its call."""

    def _source_level(self, item, slot, label, scope) -> float:
        """A waveform argument; a pressure level far from the usual is a located warning."""
        value = self._number(item, slot, label, scope)
        if slot == "pressure":
            plausible.check_level(value, item, label.split()[-1])
        return value

    def _waveform(self, call: Call, slot, scope, label):
        from ..physics import waveforms as wf

        kind = call.name.upper()
        diff = "pressure_difference" if slot == "pressure" else slot
        layouts = {
            "STEP": (wf.Step, [("initial", slot), ("final", slot), ("at", "time"), ("rise", "time")], 2),
            "PULSE": (wf.Pulse, [("low", slot), ("high", slot), ("delay", "time"), ("rise", "time"),
                                 ("fall", "time"), ("width", "time"), ("period", "time")], 2),
            "SIN": (wf.Sine, [("offset", slot), ("amplitude", diff), ("frequency", "frequency"),
                              ("delay", "time"), ("damping", "frequency"),
                              ("phase", "dimensionless")], 3),
        }
        if kind == "PWL" and len(call.args) == 1 and isinstance(call.args[0], Pair) and \
                isinstance(call.args[0].key, Word) and call.args[0].key.text.lower() == "file":
            times, values = read_data_file(call.args[0].value, self.source.policy,
                                           ("time", slot), self.options, label, strict=False)
            return wf.PiecewiseLinear(tuple(times), tuple(values))
        if kind == "PWL":
            args = call.args
            if not isinstance(args, RawArgs) and any(isinstance(a, Pair) for a in args):
                raise _err("PWL takes time value pairs", call)
            if len(args) < 2 or len(args) % 2:
                raise _err(f"PWL needs pairs of time and value, got {len(args)} number(s)", call,
                           "e.g. PWL(0 96kPa 1 296kPa 2 296kPa)")
            times = column(args, 0, "time", lambda a, slot: self._number(a, slot, "PWL time", scope),
                           self._converter("PWL time")) if isinstance(args, RawArgs) else \
                [self._number(a, "time", "PWL time", scope) for a in args[0::2]]
            values = [self._source_level(a, slot, "PWL value", scope) for a in args[1::2]]
            for i in range(1, len(times)):
                if times[i] < times[i - 1]:
                    raise _err("PWL times must not decrease", args[2 * i],
                               "write corners in time order: PWL(0 96 1 200 …)")
            return wf.PiecewiseLinear(tuple(times), tuple(values))
        if kind == "DC" and len(call.args) == 1:
            return self._number(call.args[0], slot, label, scope)
        if kind not in layouts:
            raise _err(f"unknown waveform {call.name!r}", call,
                       _close(kind, list(layouts) + ["PWL"]) or "known: STEP, PULSE, PWL, SIN")
        cls, fields_, required = layouts[kind]
        values, pos = {}, 0
        for a in call.args:
            if isinstance(a, Pair):
                k = a.key.text.lower() if isinstance(a.key, Word) else ""
                match = [f for f in fields_ if f[0] == k]
                if not match:
                    raise _err(f"unknown {kind} argument {k!r}", a.key,
                               _close(k, [f[0] for f in fields_]) or
                               "known: " + ", ".join(f[0] for f in fields_))
                f = match[0]
                values[f[0]] = self._source_level(a.value, f[1], f"{kind} {f[0]}", scope)
            else:
                if pos >= len(fields_):
                    raise _err(f"too many arguments for {kind} (at most {len(fields_)})", a)
                f = fields_[pos]
                values[f[0]] = self._source_level(a, f[1], f"{kind} {f[0]}", scope)
                pos += 1
        missing = [f[0] for f in fields_[:required] if f[0] not in values]
        if missing:
            raise _err(f"{kind} needs {', '.join(missing)}", call,
                       f"{kind}(" + " ".join(f[0] for f in fields_) + ")")
        try:
            return cls(**values)
        except PneunetError as err:
            raise _err(err.message, call, err.hint) from None
