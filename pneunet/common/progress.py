"""Progress bars (tqdm) on stderr, drawn only when it is a terminal."""
from __future__ import annotations


def progress_bar(enabled: bool = True, **kwargs):
    """A tqdm bar (``kwargs`` as for tqdm), disabled unless ``enabled`` and stderr is a
    terminal: no bar in log files or pipes.  During a simulation it draws on the
    user's stderr, not into the solver-output capture."""
    from tqdm.auto import tqdm

    from .solver_messages import user_stderr

    stream = user_stderr()
    try:
        terminal = stream.isatty()
    except (AttributeError, ValueError):
        terminal = False
    return tqdm(file=stream, disable=not (enabled and terminal), **kwargs)
