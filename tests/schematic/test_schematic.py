"""Issue 36: every shipped circuit draws without overlapping symbols or labels, with every
element and node named on it; arrays are drawn once with their count; --op and --at write
the analysis' own numbers on the drawing."""
import re
import shutil
import subprocess
import sys
from pathlib import Path
from xml.etree import ElementTree

import pytest

from pneunet import Circuit
from pneunet.interfaces.cli import main
from pneunet.netlist import parse_file, parse_netlist
from pneunet.physics import elements
from pneunet.design.paper_circuits import flow_amplifier
from pneunet.interfaces.schematic import collapse, draw
from pneunet.interfaces.schematic.geometry import Layout

ROOT = Path(__file__).resolve().parents[2]
NETLISTS = sorted((ROOT / "netlists").glob("*.pn")) + sorted((ROOT / "examples").rglob("*.pn"))
SVG = "{http://www.w3.org/2000/svg}"
#: one element of every built-in kind (tests/netlist/test_every_signal.py)
EVERY_KIND = (ROOT / "tests" / "every_kind_gas.pn").read_text() + 'R4 b f 1\nVf f 1mL\nX2 f atm atm axi\n.tran 10ms 0.2s\n'
LIQUID = """.options fluid=water
P1 pump 3bar
orifice O1 pump act 0.5mm
accumulator A1 act 20mL 0.05mL/kPa
laminar_tube T1 act atm length=1m diameter=1mm
"""


def _examples():
    sys.path.insert(0, str(ROOT / "examples" / "oscillator"))
    try:
        from oscillator import build
    finally:
        sys.path.pop(0)
    return {"examples/oscillator": build(1.132), "examples/amplifier": flow_amplifier("mirror")}


CIRCUITS = ({p.relative_to(ROOT).as_posix(): p for p in NETLISTS}
            | {"every kind": EVERY_KIND, "liquid kinds": LIQUID} | dict.fromkeys(("examples/oscillator",
                                                           "examples/amplifier")))


def _circuit(name):
    if name in ("every kind", "liquid kinds"):
        return parse_netlist(CIRCUITS[name]).circuit
    if name.startswith("examples/") and not name.endswith(".pn"):
        return _examples()[name]
    return parse_file(CIRCUITS[name]).circuit


def _texts(svg: str) -> list[str]:
    return [t.text for t in ElementTree.fromstring(svg).iter(SVG + "text")]


#: (circuit, subcircuit instances as boxes?): a netlist with subcircuits draws both ways
MODES = [(name, boxes) for name in CIRCUITS for boxes in (False, True)
         if not boxes or name.endswith(".pn") and ".subckt" in CIRCUITS[name].read_text()]


@pytest.mark.parametrize("name, boxes", MODES)
def test_every_circuit_draws_without_overlaps_and_names_everything(name, boxes):
    circuit = _circuit(name)
    instances = parse_file(CIRCUITS[name]).instances if boxes else []
    lay = draw(circuit, instances=instances)
    assert lay.overlaps() == []
    texts = _texts(lay.svg)
    sch = collapse(circuit, instances)
    # every element is drawn by exactly one part; a lone element under its own name
    drawn = [n for part in sch.parts.values() for n in part.names]
    assert sorted(drawn) == sorted(circuit.elements)
    for part in sch.parts.values():
        shown = [t for t in texts if t.split(" ×")[0] == part.label]
        assert shown, part.label
        if "[" not in part.label and part.segments == 1 and not part.pins:
            assert part.names == [part.label]
        assert (f" ×{part.count}" in shown[0]) == (part.count > 1)
    # every node (but the reference, drawn as exhausts) is named, arrays by their ranges;
    # a box hides the nodes inside its instance, not those on its ports
    top = [i for i in instances if i.depth == 0]
    inside = {n for i in top for n in i.elements}
    pneumatic = {n for e in circuit.elements.values() if e.name not in inside for n, port in
                 zip(e.nodes, elements.family(e.kind).ports)
                 if port not in ("x", "v", "heat", "state") and not circuit.is_reference(n)}
    pneumatic |= {n for i in top for n in i.ports.values() if not circuit.is_reference(n)}
    tubes = {e.name.rpartition(".s")[0] for e in circuit.elements.values() if e.kind == "tube"}
    for node in {n for n in pneumatic if not re.fullmatch(r"(.+)\.\d+", n)
                 or re.fullmatch(r"(.+)\.\d+", n).group(1) not in tubes}:
        if "[" in node:
            stem = re.sub(r"\[\d+\]", "[", node)
            assert any(re.sub(r"\[[^\]]*\]", "[", t) == stem for t in texts), node
        else:
            assert node in texts, node


def test_arrays_are_drawn_once_with_their_count():
    lay = draw(parse_file(ROOT / "netlists/demux3.pn").circuit)
    texts = _texts(lay.svg)
    for label in ("Aact[0:7] ×8", "Rleak[0:7] ×8", "Xcell[0:7].Vn1 ×8", "act[0:7]",
                  "Xinv[0:2].Xv ×3", "a_1[0:2]", "Xcell[0,2,…,6].X0 ×4", "Xcell[1,3,…,7].X0 ×4"):
        assert label in texts
    # a netlist of 1000 cells is one cell ×1000
    text = "P1 supply 300kPa\n.subckt C s\nR1 s t 1\nVt t 1mL\n.ends\nXc[0:999] supply C\n"
    sch = collapse(parse_netlist(text).circuit)
    assert sorted(p.label for p in sch.parts.values()) == ["P1", "Xc[0:999].R1", "Xc[0:999].Vt"]
    assert {p.count for p in sch.parts.values()} == {1, 1000}
    # two of a kind are two as well; one element is never "×1"
    texts = _texts(draw(parse_netlist("P1 s 300kPa\nR[0:1] s atm 1\n").circuit).svg)
    assert "R[0:1] ×2" in texts and "P1" in texts


def test_a_tube_is_one_symbol_with_its_segments():
    c = Circuit("t")
    c.pressure_source("P", "a", 200)
    c.tube("T1", "a", "b", length="1m", diameter="4mm", segments=4)
    c.volume("V", "b", V=10)
    part = collapse(c).parts["T1"]
    assert (part.ports, part.segments, part.count) == ({"a": "a", "b": "b"}, 4, 1)
    assert "4 segments" in " ".join(_texts(c.draw().svg))


def test_overlaps_and_crossings_are_measured():
    """The measures the tests rely on see what they should."""
    lay = Layout(100, 100, [], [("symbol", "A", (0, 0, 10, 10)), ("label", "B", (9, 9, 20, 20)),
                                ("label", "C", (20, 0, 30, 9))], [])
    assert lay.overlaps() == [("symbol A", "label B")]
    lay.wires = [("n1", [(0, 5), (10, 5)], False), ("n2", [(5, 0), (5, 10)], True),
                 ("n1", [(7, 0), (7, 10)], False)]
    assert lay.crossings() == 1          # the same net joining itself is no crossing


def test_flow_runs_left_to_right_and_control_lines_are_dashed():
    lay = draw(parse_file(ROOT / "netlists/oscillator.pn").circuit)
    x = {name: box[0] for what, name, box in lay.boxes if what == "symbol"}
    assert x["PH"] < x["X1"] < x["Rout"] < x["Rvent"]
    dashed = [w for w in lay.wires if w[2]]
    assert [w[0] for w in dashed] == ["tank"]          # X1's pilot line, to the tank
    assert all(not w[2] for w in lay.wires if w[0] != "tank")
    assert 'class="ctrl"' in lay.svg and "stroke-dasharray" in lay.svg


def _number(texts, prefix):
    return [float(t[len(prefix):].split()[0]) for t in texts if t.startswith(prefix)]


def test_operating_point_numbers_are_on_the_drawing(tmp_path, capsys):
    path = ROOT / "netlists/oscillator_rout0.pn"
    op = parse_file(path).circuit.op(stability=False)
    out = tmp_path / "op.svg"
    assert main(["draw", str(path), "-o", str(out), "--op"]) == 0
    assert "0 overlaps" in capsys.readouterr().out
    texts = _texts(out.read_text())
    assert sorted(_number(texts, "p=")) == pytest.approx(sorted(op.pressures.values()), rel=1e-3)
    assert sorted(_number(texts, "ṁ=")) == pytest.approx(sorted(op.flows.values()), rel=1e-3)


def test_transient_numbers_at_a_time_are_on_the_drawing(tmp_path):
    deck = parse_file(ROOT / "netlists/oscillator.pn")
    sol = deck.circuit.tran(3.0, t_step=0.01)
    expect = sol.at(3.0)
    texts = _texts(deck.circuit.draw(results=(sol, 3.0)).svg)
    assert sorted(_number(texts, "p=")) == pytest.approx(
        sorted(v for k, v in expect.items() if k.startswith("p_")), rel=1e-3)
    out = tmp_path / "at.svg"
    assert main(["draw", str(ROOT / "netlists/oscillator.pn"), "-o", str(out), "--at", "3s"]) == 0
    assert _number(_texts(out.read_text()), "p=") == pytest.approx(_number(texts, "p="), rel=2e-3)


@pytest.mark.parametrize("args, message", [
    (["-o", "x.txt"], "unknown drawing format"),
    (["-o", "x.svg", "--at", "31s"], "outside the .tran interval"),
    (["-o", "x.svg", "--at", "soon"], "not a time"),
])
def test_bad_requests_are_exit_2_with_a_message(args, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["draw", str(ROOT / "netlists/oscillator.pn"), *args]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())


def test_check_draws_before_anything_is_simulated(tmp_path, capsys):
    out = tmp_path / "demux3.svg"
    assert main(["check", str(ROOT / "netlists/demux3.pn"), "--draw", str(out)]) == 0
    assert {"Aact[0:7] ×8", "Xcell[0:7] ×8"} <= set(_texts(out.read_text()))
    assert main(["check", str(ROOT / "netlists/demux3.pn"), "--draw", str(out), "--expand"]) == 0
    assert "Xcell[0:7].Vn1 ×8" in _texts(out.read_text())
    assert main(["check", str(ROOT / "netlists/demux3.pn"), "--draw", "x.gif"]) == 2
    assert "unknown drawing format" in capsys.readouterr().err


def test_at_needs_a_transient(tmp_path, capsys):
    net = tmp_path / "op.pn"
    net.write_text("P1 a 200kPa\nR1 a atm 1\n.op\n")
    assert main(["draw", str(net), "-o", str(tmp_path / "x.svg"), "--at", "1s"]) == 2
    assert "has no .tran" in capsys.readouterr().err


@pytest.mark.parametrize("suffix, magic", [(".png", b"\x89PNG"), (".pdf", b"%PDF")])
def test_png_and_pdf(suffix, magic, tmp_path):
    out = tmp_path / f"c{suffix}"
    assert main(["draw", str(ROOT / "netlists/inverter.pn"), "-o", str(out)]) == 0
    assert out.read_bytes().startswith(magic)


def test_jupyter_shows_the_schematic():
    c = Circuit("rc")
    c.pressure_source("PS", "s", 300)
    c.resistor("R1", "s", "t", R=1)
    c.volume("V1", "t", V=5)
    svg = c._repr_svg_()
    assert svg.startswith("<svg") and {"PS", "R1", "V1", "s", "t"} <= set(_texts(svg))
    assert {"INV", "X1", "X2"} <= set(_texts(parse_file(ROOT / "netlists/inverter.pn")._repr_svg_()))


def test_a_browser_renders_the_drawing(tmp_path):
    """Headless Chromium draws the SVG: the picture holds dark pixels where the layout put
    the supply's symbol and none outside the drawing's size."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        pytest.skip("no chromium on this machine (apt-get install chromium): not rendered")
    lay = draw(parse_file(ROOT / "netlists/oscillator.pn").circuit, tmp_path / "osc.svg")
    png = tmp_path / "osc.png"
    w, h = int(lay.width) + 40, int(lay.height) + 40
    subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                    f"--screenshot={png}", f"--window-size={w},{h}",
                    (tmp_path / "osc.svg").as_uri()], capture_output=True, timeout=60)
    from matplotlib.image import imread

    img = imread(png)[..., :3].mean(axis=2)
    x0, y0, x1, y1 = next(b for what, name, b in lay.boxes if what == "symbol" and name == "PH")
    left = img[int(y0):int(y1) + 1, int(x0):int((x0 + x1) / 2)]       # the source's circle,
    assert left.min() < 0.3                                              # not the wire on its right
    assert img[int(lay.height) + 5:, :].min() > 0.9                       # nothing below it


def _pin(lay, svg_texts_at, box, name):
    """(x, y) of the pin text ``name`` inside the box drawn for ``box``."""
    x0, y0, x1, y1 = next(b for what, n, b in lay.boxes if what == "symbol" and n == box)
    return [(x, y) for x, y, t in svg_texts_at if t == name and x0 < x < x1 and y0 < y < y1]


def _texts_at(svg):
    return [(float(t.get("x")), float(t.get("y")), t.text)
            for t in ElementTree.fromstring(svg).iter(SVG + "text")]


def test_subcircuit_instances_are_boxes_wired_by_their_ports():
    deck = parse_file(ROOT / "netlists/inverter.pn")
    x1 = next(i for i in deck.instances if i.name == "X1")
    assert (x1.subckt, x1.ports, x1.params, x1.elements, x1.depth) == (
        "INV", {"supply": "supply", "in": "in", "out": "out1"}, {"Rp": 20.0},
        ("X1.Xv", "X1.Rpull", "X1.Vout"), 0)
    lay = deck.draw()
    texts, at = _texts(lay.svg), _texts_at(lay.svg)
    assert {"X1", "X2", "INV", "Rp=20"} <= set(texts) and not any("." in t for t in texts)
    box = {n: b for what, n, b in lay.boxes if what == "symbol"}
    assert box["Pin"][2] < box["X1"][0] < box["X1"][2] < box["X2"][0]     # flow left to right
    for inst in ("X1", "X2"):
        (sx, sy), = _pin(lay, at, inst, "supply")
        (ix, iy), = _pin(lay, at, inst, "in")
        (ox, oy), = _pin(lay, at, inst, "out")
        assert sx < (box[inst][0] + box[inst][2]) / 2 < ox and ix < ox    # inputs left, out right
        assert abs(sy - iy) >= 16 and box[inst][1] < min(sy, iy, oy)       # pins apart, inside
    # every wire meets a box's edge head-on, at a pin
    for net, pts, dashed in lay.wires:
        for end, prev in ((pts[0], pts[1]), (pts[-1], pts[-2])):
            name = next((n for n in ("X1", "X2") if min(abs(end[0] - box[n][0]),
                                                        abs(end[0] - box[n][2])) < 0.5), None)
            if name:
                assert prev[1] == pytest.approx(end[1]), (net, pts)                # horizontal
    # each wire ends on its pin: X2's "in" is the dashed line from out1, X1's "out" solid
    ends = {(net, dashed): pts[-1] if pts[-1][0] > pts[0][0] else pts[0]
            for net, pts, dashed in lay.wires}
    (ix, iy), = _pin(lay, at, "X2", "in")
    ex, ey = ends["out1", True]
    assert ex == pytest.approx(box["X2"][0], abs=0.5) and ey == pytest.approx(iy - 4, abs=0.5)
    (ox, oy), = _pin(lay, at, "X1", "out")
    sx, sy = next(pts[0] if pts[0][0] < pts[-1][0] else pts[-1]
                  for net, pts, dashed in lay.wires if net == "out1" and not dashed)
    assert sx == pytest.approx(box["X1"][2], abs=0.5) and sy == pytest.approx(oy - 4, abs=0.5)
    # expanded, the same netlist shows the valves and resistors inside
    expanded = _texts(deck.draw(expand=True).svg)
    assert {"X1.Xv", "X2.Rpull", "X1.Vout"} <= set(expanded) and "INV" not in expanded


def test_an_array_of_instances_is_one_box_with_its_count():
    lay = parse_file(ROOT / "netlists/demux3.pn").draw()
    texts = _texts(lay.svg)
    assert {"Xcell[0:7] ×8", "Xinv[0:2] ×3", "CELL", "INV", "Aact[0:7] ×8"} <= set(texts)
    assert sum(1 for what, *_ in lay.boxes if what == "symbol") == 6
    # a port whose members reach different nodes has a pin per node: c0 on a_0 and on a_1
    assert [_texts(lay.svg).count(f"c{i}") for i in range(3)] == [2, 2, 2]
    texts = _texts(parse_file(ROOT / "netlists/oscillators100.pn").draw().svg)
    assert {"Xosc[0:99] ×100", "V=100…298", "OSC", "tank[0:99]"} <= set(texts)


def test_nested_instances_and_ports_on_the_reference(tmp_path):
    net = tmp_path / "nested.pn"
    net.write_text("P1 s 200kPa\n.subckt LEAK a b R=1\nR1 a m {R}\nVm m 1mL\nR2 m b {R}\n.ends\n"
                   ".subckt TWO a\nX1 a atm LEAK R=2\nX2 a 0 LEAK\n.ends\nXt s TWO\nXa s atm LEAK\n"
                   "Xk[0:3] s k[0:3] LEAK R={index+1}\nVk[0:3] k[0:3] 1mL\n")
    deck = parse_file(net)
    assert [(i.name, i.depth) for i in deck.instances] == [
        ("Xt", 0), ("Xt.X1", 1), ("Xt.X2", 1), ("Xa", 0), ("Xk[0]", 0), ("Xk[1]", 0), ("Xk[2]", 0),
        ("Xk[3]", 0)]
    assert next(i for i in deck.instances if i.name == "Xt").elements == (
        "Xt.X1.R1", "Xt.X1.Vm", "Xt.X1.R2", "Xt.X2.R1", "Xt.X2.Vm", "Xt.X2.R2")
    lay = deck.draw()
    texts = _texts(lay.svg)
    assert {"Xt", "TWO", "Xk[0:3] ×4", "R=1…4", "k[0:3]"} <= set(texts) and lay.overlaps() == []
    box = {n: b for what, n, b in lay.boxes if what == "symbol"}
    assert sorted(box) == ["P1", "Vk[0:3]", "Xa", "Xk[0:3]", "Xt"]   # the nested ones inside Xt
    # Xa's port b on the reference: an exhaust on the box's right, inside its symbol's box
    (bx, by), = _pin(lay, _texts_at(lay.svg), "Xa", "b")
    assert box["Xa"][2] - bx > 18
    sch = collapse(deck.circuit, deck.instances)
    assert sorted(n for p in sch.parts.values() for n in p.names) == sorted(deck.circuit.elements)
    assert box["P1"][2] < box["Xt"][0] and box["P1"][2] < box["Xk[0:3]"][0]   # loads right
    assert "Xt.X1.R1" in _texts(deck.draw(expand=True).svg)


def test_a_box_with_a_source_inside_feeds_its_node_from_the_left(tmp_path):
    net = tmp_path / "supply.pn"
    net.write_text(".subckt SUP out\nPs s 300kPa\nR1 s out 1\n.ends\nXs feed SUP\n"
                   "R2 feed tank 1\nV1 tank 5mL\n")
    lay = parse_file(net).draw()
    box = {n: b for what, n, b in lay.boxes if what == "symbol"}
    node = {n: b for what, n, b in lay.boxes if what == "node"}
    assert box["Xs"][2] < node["feed"][0] < box["R2"][0]


def test_a_box_is_placed_where_its_wires_balance(tmp_path):
    """A box alone in its layer sits where the rise of its wires (pin end minus node end)
    sums to zero: the y placement pulls each pin, not the box's top, to its node."""
    net = tmp_path / "split.pn"
    net.write_text("P1 s 300kPa\n.subckt SPLIT a b c\nR1 a b 1\nR2 a c 1\n.ends\n"
                   "X1 s b c SPLIT\nVb b 1mL\nVc c 1mL\n")
    lay = parse_file(net).draw()
    x0, y0, x1, y1 = next(b for what, n, b in lay.boxes if what == "symbol" and n == "X1")
    rise = []
    for net_name, pts, _ in lay.wires:
        for end, other in ((pts[0], pts[-1]), (pts[-1], pts[0])):
            if min(abs(end[0] - x0), abs(end[0] - x1)) < 0.5 and y0 <= end[1] <= y1:
                rise.append(end[1] - other[1])
    assert len(rise) == 3 and abs(sum(rise)) < 2.0 and max(map(abs, rise)) > 8  # not trivial


def test_operating_point_on_boxes_is_their_ports_pressures(tmp_path, capsys):
    path = ROOT / "netlists/inverter.pn"
    op = parse_file(path).circuit.op(stability=False)
    out = tmp_path / "op.svg"
    assert main(["draw", str(path), "-o", str(out), "--op"]) == 0
    texts = _texts(out.read_text())
    assert sorted(_number(texts, "p=")) == pytest.approx(sorted(op.pressures.values()), rel=1e-3)
    # flows only on the drawn elements (the sources), none on a box
    assert sorted(_number(texts, "ṁ=")) == pytest.approx(
        sorted(v for k, v in op.flows.items() if "." not in k), rel=1e-3)
    assert main(["draw", str(path), "-o", str(out), "--expand"]) == 0
    assert "X1.Xv" in _texts(out.read_text())


#: wire crossings a drawing may have: the paper's circuits, as boxes and expanded. Measured
#: 0/0, 0/0, 1/1, 0/0, 0/5, 0/14; without grandalf's crossing reduction 0/0, 5/5, 1/1, 0/0,
#: 1/24, 1/81; with it but from one edge order only 0/0, 2/2, 1/1, 0/2, 0/15, 0/33.
CROSSINGS = {"fill_time": (0, 0), "amplifier": (1, 1), "oscillator": (1, 1),
             "inverter": (0, 0), "demux3": (0, 8), "demux6": (0, 20)}


@pytest.mark.parametrize("name", CROSSINGS)
def test_the_layered_layout_keeps_crossings_few(name):
    deck = parse_file(ROOT / "netlists" / f"{name}.pn")
    measured = tuple(deck.draw(expand=expand).crossings() for expand in (False, True))
    assert all(m <= limit for m, limit in zip(measured, CROSSINGS[name])), measured
