"""How many elements a netlist makes, counted before any is made: a nest of subcircuit
arrays can ask for millions, and ``max_elements`` then stops it at once instead of after
seconds of elaboration.  A count that needs parameter values (a range with ``{}``) is
taken as one copy, so the count never exceeds what elaboration makes."""
from __future__ import annotations

from ..common.errors import NetlistError
from .arrays import split_range
from .syntax import Pair, Word


def check_size(source, kind_words, limits) -> None:
    """A NetlistError at the top-level line with which the count passes ``max_elements``."""
    memo: dict = {}
    total = 0
    for st in source.top:
        made = _count(st, source, kind_words, limits, memo, ())
        total += made
        if total > limits.max_elements:
            raise NetlistError(f"this line makes {made} elements, {total} with the lines "
                               f"before ({limits.exceeded('max_elements')})",
                               span=_name(st, kind_words)[0].span,
                               hint=limits.hint("max_elements"))


def _name(st, kind_words):
    """(name item, the items after it) of an element line, either form."""
    head, rest = st.items[0], st.items[1:]
    if len(head.text) > 1 and head.text.lower() in kind_words and rest \
            and isinstance(rest[0], Word):
        return rest[0], rest[1:]
    return head, rest


def _count(st, source, kind_words, limits, memo, stack) -> int:
    if st.is_directive or not isinstance(st.items[0], Word):
        return 0
    name, rest = _name(st, kind_words)
    copies = _copies(name, limits)
    positional = [it for it in rest if not isinstance(it, Pair)]
    sub = None
    if name is st.items[0] and name.text[:1].lower() == "x" and positional \
            and isinstance(positional[-1], Word):
        sub = source.subckts.get(positional[-1].text.lower())
    if sub is None:
        return copies
    key = sub.name.lower()
    if key in stack or len(stack) > limits.max_subckt_depth:
        return 0  # recursion or depth: reported when the instance is elaborated
    if key not in memo:
        memo[key] = sum(_count(s, source, kind_words, limits, memo, (*stack, key))
                        for s in sub.body)
    return copies * memo[key]


def _copies(name, limits) -> int:
    if "{" in name.text:
        return 1
    try:
        split = split_range(name.text, name, limits)
    except NetlistError:
        return 1  # a bad range is reported when the line is elaborated
    return 1 if split is None else len(split[1])
