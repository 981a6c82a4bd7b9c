"""Errors at a netlist item, and did-you-mean hints (shared by the elaboration modules)."""
from __future__ import annotations

import difflib

from ..common.errors import NetlistError, SourceSpan


def error_at(msg, item_or_span, hint=None):
    """A NetlistError at an item; a message quoting a long word is cut (the caret shows it)."""
    span = item_or_span if isinstance(item_or_span, SourceSpan) else item_or_span.span
    if len(msg) > 300:
        msg = msg[:299] + "…"
    return NetlistError(msg, span=span, hint=hint)


def did_you_mean(word, choices):
    m = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f"did you mean {m[0]!r}?" if m else None
