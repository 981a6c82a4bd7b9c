"""Every file or folder a command writes, checked when its option is read (argparse
``type=``), before any work: a name too long, a folder where a file goes (or the reverse),
a file where a folder must be, an unwritable or read-only place, an unknown plot format.
Nothing is created by the check; a failure while writing later (a full disk, ``/dev/full``)
is reported by :func:`pneunet.interfaces.cli.main` as one message naming the file.
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

#: bytes in one file or folder name, and in a whole path (Linux's NAME_MAX, PATH_MAX)
NAME_MAX, PATH_MAX = 255, 4096
#: what matplotlib writes, by suffix (checked without importing it)
PLOT_FORMATS = ("png", "pdf", "svg", "svgz", "eps", "ps", "jpg", "jpeg", "tif", "tiff",
                "webp", "gif", "pgf", "raw", "rgba", "avif")


def output_file(plot: bool = False):
    """An argparse ``type`` for a file a command writes (``plot``: its suffix must be a
    format matplotlib writes)."""
    def check(text: str) -> str:
        path = _common(text)
        if path.is_dir():
            raise argparse.ArgumentTypeError(f"{text} is a folder; name a file")
        if plot and path.suffix.lower().lstrip(".") not in PLOT_FORMATS:
            raise argparse.ArgumentTypeError(
                f"{text}: unknown plot format {path.suffix or '(no suffix)'!r}; use .png, "
                ".pdf or .svg (" + ", ".join(PLOT_FORMATS) + ")")
        if path.exists() and not os.access(path, os.W_OK):
            raise argparse.ArgumentTypeError(f"cannot write {text}: permission denied")
        return text
    return check


def output_folder(text: str) -> str:
    """An argparse ``type`` for a folder a command writes files into."""
    path = _common(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file; name a folder (new or existing)")
    return text


def _common(text: str) -> Path:
    """The path, after the checks a file and a folder share: a usable name whose nearest
    existing folder can be written in."""
    if not text.strip() or "\0" in text:
        raise argparse.ArgumentTypeError(f"{text!r} is not a file name")
    raw = os.fsencode(text)
    long = max(raw.split(b"/"), key=len)
    if len(long) > NAME_MAX or len(raw) > PATH_MAX:
        raise argparse.ArgumentTypeError(
            f"name too long: {len(long)} bytes in one name ({NAME_MAX} at most), "
            f"{len(raw)} in the path ({PATH_MAX} at most)")
    path = Path(text)
    parent = path.parent if not path.is_dir() else path
    while not parent.exists() and parent != parent.parent:
        if parent.is_symlink():
            raise argparse.ArgumentTypeError(f"{parent} is a broken symbolic link")
        parent = parent.parent
    if not parent.is_dir():
        raise argparse.ArgumentTypeError(f"{parent} is a file, not a folder: cannot write "
                                         f"{text}")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"cannot write in {parent} (read-only or no "
                                         "permission)")
    return path
