"""Element symbols in the spirit of ISO 1219-1 (fluid power), drawn from primitives.

A :class:`Symbol` has a size (px), its ports (``"left"``, ``"right"``; a valve's pilot
``"top"``) and primitives in its own coordinates (origin top left, y down):
``("path", points, closed, fill, dashed)`` and ``("circle", centre, radius, fill)``.
Two-port elements pass flow from their first port (left) to their second (right); one-port
elements (sources, volumes, actuators) have their port on one side.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

LINE, DASH = False, True


@dataclass(frozen=True)
class Symbol:
    w: float
    h: float
    prims: tuple
    port: str = "both"          # "both" (two-port), "right" (a source), "left" (a load)
    pilot: bool = False         # a pilot port on top (membrane valve)
    mid: float | None = None    # y of the flow line (default h/2)

    @property
    def flow_y(self) -> float:
        return self.h / 2 if self.mid is None else self.mid


def _p(points, closed=False, fill=None, dashed=LINE):
    return ("path", tuple(points), closed, fill, dashed)


def _arc(cx, cy, r, a0, a1, n=10):
    return [(cx + r * math.cos(math.radians(a0 + (a1 - a0) * i / n)),
             cy + r * math.sin(math.radians(a0 + (a1 - a0) * i / n))) for i in range(n + 1)]


def _leads(w, h, x0, x1):
    """The flow line from the left port to x0 and from x1 to the right port."""
    return [_p([(0, h / 2), (x0, h / 2)]), _p([(x1, h / 2), (w, h / 2)])]


def _pressure_source():
    w, h = 34, 28
    return Symbol(w, h, (("circle", (13, 14), 11, None),
                         _p([(13, 5), (21, 14), (13, 23)], True, "black"),
                         _p([(24, 14), (w, 14)])), port="right")


def _flow_source():
    w, h = 40, 28
    return Symbol(w, h, (*_leads(w, h, 9, 31), ("circle", (20, 14), 11, None),
                         _p([(12, 14), (28, 14)]), _p([(23, 10), (28, 14), (23, 18)])))


def _resistor():
    w, h = 40, 20
    upper = _arc(20, -6, 14, 30, 150)
    lower = _arc(20, 26, 14, -30, -150)
    return Symbol(w, h, (*_leads(w, h, 8, 32), _p(upper), _p(lower)))


def _orifice():
    w, h = 32, 20
    return Symbol(w, h, (_p([(0, 10), (w, 10)]), _p([(14, 1), (14, 7)]), _p([(14, 13), (14, 19)]),
                         _p([(18, 1), (18, 7)]), _p([(18, 13), (18, 19)])))


def _tube(ticks=0):
    w, h = 56, 16
    prims = [*_leads(w, h, 6, 50), _p([(6, 4), (50, 4), (50, 12), (6, 12)], True)]
    prims += [_p([(6 + 44 * i / (ticks + 1), 4), (6 + 44 * i / (ticks + 1), 12)])
              for i in range(1, ticks + 1)]
    return Symbol(w, h, tuple(prims))


def _valve():
    """2/2 valve, normally open, pilot-operated against a spring: two squares, the left
    one (rest position) passes flow; the pilot (dashed, filled triangle) acts from the top."""
    w, h = 52, 44
    y0, y1 = 14, 36                    # squares' top and bottom
    prims = [_p([(0, 25), (8, 25)]), _p([(44, 25), (w, 25)]),
             _p([(8, y0), (44, y0), (44, y1), (8, y1)], True), _p([(26, y0), (26, y1)]),
             _p([(8, 25), (26, 25)]), _p([(20, 22), (26, 25), (20, 28)], True, "black"),
             _p([(30, 25), (40, 25)]), _p([(35, 25), (35, 21)]),       # closed: ⊥
             _p([(26, 0), (26, 8)], dashed=DASH), _p([(22, 8), (30, 8), (26, y0)], True, "black"),
             _p([(44, 30), (46, 27), (48, 33), (50, 27), (52, 30)])]   # spring
    return Symbol(w, h, tuple(prims), pilot=True, mid=25)


def _check_valve(double=False):
    w, h = 40, 24
    prims = [_p([(0, 12), (12, 12)]), _p([(28, 12), (w, 12)]),
             _p([(24, 3), (12, 12), (24, 21)]), ("circle", (23, 12), 5, None)]
    if double:
        prims.append(_p([(28, 3), (16, 12), (28, 21)]))
    return Symbol(w, h, tuple(prims))


def _reservoir(inner=None):
    w, h = 44, 22
    outline = _arc(14, 11, 9, 90, 270) + _arc(34, 11, 9, -90, 90)
    prims = [_p([(0, 11), (5, 11)]), _p(outline, True)]
    if inner == "heat":
        prims.append(_p([(14, 11), (18, 7), (22, 15), (26, 7), (30, 15), (34, 11)]))
    return Symbol(w, h, tuple(prims), port="left")


def _actuator():
    w, h = 56, 22
    return Symbol(w, h, (_p([(0, 11), (6, 11)]), _p([(6, 3), (40, 3), (40, 19), (6, 19)], True),
                         _p([(18, 3), (18, 19)]), _p([(18, 11), (w, 11)])), port="left")


def _accumulator():
    w, h = 34, 36
    outline = _arc(22, 12, 8, 180, 360) + _arc(22, 24, 8, 0, 180)
    return Symbol(w, h, (_p([(0, 18), (14, 18)]), _p(outline, True), _p([(14, 18), (30, 18)])),
                  port="left", mid=18)


def _elastic():
    w, h = 44, 24
    zig = [(8 + 4 * i, 3 if i % 2 else 21) for i in range(9)]
    return Symbol(w, h, (_p([(0, 12), (8, 12)]), _p(zig), _p([(40, 3), (40, 21)])), port="left")


def _mckibben():
    """A braided sleeve (crossed lines in a capsule) pulling a load (filled block)."""
    w, h = 64, 26
    prims = [_p([(0, 13), (6, 13)]), _p([(6, 4), (42, 4), (42, 22), (6, 22)], True)]
    prims += [_p([(6 + 9 * i, 4), (15 + 9 * i, 22)]) for i in range(4)]
    prims += [_p([(15 + 9 * i, 4), (6 + 9 * i, 22)]) for i in range(4)]
    prims += [_p([(42, 13), (52, 13)]), _p([(52, 6), (62, 6), (62, 20), (52, 20)], True, "black")]
    return Symbol(w, h, tuple(prims), port="left")


def _box():
    w, h = 40, 24
    return Symbol(w, h, (*_leads(w, h, 4, 36), _p([(4, 2), (36, 2), (36, 22), (4, 22)], True)))


def exhaust(x, y, direction=1):
    """ISO exhaust (an open triangle) at the end of a stub from (x, y); ``direction`` +1
    right, -1 left, 0 up (a vented pilot).  Returns primitives and the bounding box."""
    if direction == 0:
        prims = (_p([(x, y), (x, y - 8)], dashed=DASH), _p([(x - 6, y - 8), (x + 6, y - 8), (x, y - 16)], True))
        return prims, (x - 6, y - 16, x + 6, y)
    d = direction
    prims = (_p([(x, y), (x + 8 * d, y)]), _p([(x + 8 * d, y - 6), (x + 8 * d, y + 6), (x + 18 * d, y)], True))
    return prims, (min(x, x + 18 * d), y - 6, max(x, x + 18 * d), y + 6)


EXHAUST_W = 18

_BUILDERS = {
    "pressure_source": _pressure_source, "flow_source": _flow_source,
    "resistor": _resistor, "orifice": _orifice, "pipe": _tube, "laminar_tube": _tube,
    "tube": lambda: _tube(ticks=2), "tube_line": _tube, "valve": _valve, "check_valve": _check_valve,
    "hysteretic_check_valve": lambda: _check_valve(double=True),
    "volume": _reservoir, "thermal_volume": lambda: _reservoir("heat"),
    "thermal_chamber": lambda: _reservoir("heat"), "thermal_inlet": _resistor,
    "actuator": _actuator, "accumulator": _accumulator, "pv_volume": _elastic,
    "pv_volume_state": _elastic,
    "mckibben": _mckibben, "mckibben_static": _mckibben, "mckibben_damped": _mckibben,
    "mckibben_inertial": _mckibben,
}


def symbol(kind: str) -> Symbol:
    """The symbol of an element kind (a plain box for a kind from a plug-in)."""
    return _BUILDERS.get(kind, _box)()
