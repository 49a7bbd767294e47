"""A long run's progress where a person watches it: a bar of the steps done, with the
iteration of the step under way, redrawn in place on a terminal (``\\r``) or in a notebook (an
updating display); nothing where the output is captured (standard error no terminal and no
notebook).

The library's runs take ``progress=True`` (the default) for this bar, ``False`` (or ``None``)
for nothing, or a callable ``progress(index, total, scalars)`` told of each step in its place
(:func:`reporting`).
"""

from __future__ import annotations

import html
import shutil
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TextIO

StepReport = Callable[[int, int, dict[str, Any]], None]  # (index, total, scalars)
IterationReport = Callable[[int, float, float], object]  # (iteration, f, gnorm); truthy stops
WIDTH = 24  # the bar's characters
EVERY = 0.25  # seconds between two redraws within a step


class ProgressBar:
    """Steps done of ``total`` (``done`` before the first: a resumed run's), the time since
    it began and the iteration of the step under way; a step's report redraws it, an
    iteration at most every :data:`EVERY` seconds."""

    def __init__(self, total: int, done: int = 0) -> None:
        self.total, self.done = total, done
        self.iteration: int | None = None
        self.began = self.drawn = time.monotonic()

    def __call__(self, index: int, total: int, scalars: dict[str, Any]) -> None:
        """A step is done (``index`` from 0), as a run's ``progress`` is told."""
        self.done, self.total, self.iteration = index + 1, total, None
        self.draw()

    def iterate(self, iteration: int, f: float, gnorm: float) -> None:
        """An iteration of the step under way, as a solver's monitor is told."""
        self.iteration = iteration
        if time.monotonic() - self.drawn >= EVERY:
            self.draw()

    def text(self) -> str:
        """The bar's line."""
        filled = round(WIDTH * self.done / self.total) if self.total else 0
        seconds = int(time.monotonic() - self.began)
        line = (
            f"[{'#' * filled}{'-' * (WIDTH - filled)}] {self.done}/{self.total} steps, "
            f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"
        )
        if self.iteration is not None and self.done < self.total:
            line += f"; step {self.done + 1}: iteration {self.iteration}"
        return line

    def draw(self) -> None:
        """Show :meth:`text` in place of what was shown."""
        self.drawn = time.monotonic()

    def below(self) -> None:
        """Something else is about to be written (a warning): it goes below the bar."""

    def close(self) -> None:
        """The run is over: what follows goes below the bar."""
        self.below()


class TerminalBar(ProgressBar):
    """The bar as one line of ``stream`` (a terminal), rewritten after a carriage return."""

    def __init__(self, total: int, done: int, stream: TextIO) -> None:
        super().__init__(total, done)
        self.stream, self.shown = stream, False
        self.draw()

    def draw(self) -> None:
        super().draw()
        columns = shutil.get_terminal_size().columns - 1
        self.stream.write("\r" + self.text()[:columns].ljust(columns))
        self.stream.flush()
        self.shown = True

    def below(self) -> None:
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()
            self.shown = False


class NotebookBar(ProgressBar):
    """The bar as a notebook's display (an HTML ``<progress>`` and its line), updated in
    place through IPython's display handle."""

    def __init__(self, total: int, done: int, display: Any) -> None:
        super().__init__(total, done)
        self.html = display.HTML
        self.handle = display.display(self.html(self.markup()), display_id=True)

    def markup(self) -> str:
        """The display's HTML."""
        return (
            f'<progress value="{self.done}" max="{max(self.total, 1)}"></progress> '
            f"<code>{html.escape(self.text())}</code>"
        )

    def draw(self) -> None:
        super().draw()
        self.handle.update(self.html(self.markup()))


def watched_bar(total: int, done: int = 0) -> ProgressBar | None:
    """A bar where a person watches: in a notebook (an IPython kernel runs this process), or
    on standard error where it is a terminal; ``None`` where the output is captured."""
    ipython = sys.modules.get("IPython")  # a notebook has imported it; a script needs not
    shell = ipython.get_ipython() if ipython is not None else None
    if shell is not None and hasattr(shell, "kernel"):
        from IPython import display

        return NotebookBar(total, done, display)
    stream = sys.stderr
    if stream is not None and getattr(stream, "isatty", bool)():
        return TerminalBar(total, done, stream)
    return None


@contextmanager
def reporting(
    progress: StepReport | bool | None,
    monitor: IterationReport | None,
    total: int,
    done: int = 0,
    shown: bool = True,
) -> Iterator[tuple[StepReport | None, IterationReport | None]]:
    """What a run of ``total`` steps (``done`` of them already) reports each step to and the
    monitor its solver calls every iteration, for its ``progress`` argument: a callable is
    told of each step itself; ``True`` a :func:`watched_bar` (where ``shown``: the first
    rank), which shows the iterations too and calls ``monitor`` after; ``False`` or ``None``
    nothing.  A warning shown while the bar is there goes below it; the bar is closed when
    the block ends."""
    if callable(progress):
        yield progress, monitor
        return
    found = watched_bar(total, done) if progress is True and shown else None
    if found is None:
        yield None, monitor
        return
    bar, show = found, warnings.showwarning

    def watch(iteration: int, f: float, gnorm: float) -> object:
        bar.iterate(iteration, f, gnorm)
        return monitor(iteration, f, gnorm) if monitor is not None else None

    def below(*args: Any, **kwargs: Any) -> None:
        bar.below()
        show(*args, **kwargs)

    warnings.showwarning = below
    try:
        yield bar, watch
    finally:
        warnings.showwarning = show
        bar.close()
