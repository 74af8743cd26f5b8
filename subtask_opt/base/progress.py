"""Progress bars for long runs (tqdm, shown only once a run passes one second)."""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


class _NoBar:
    def update(self, n: int = 1) -> None: ...

    def set_postfix_str(self, s: str) -> None: ...

    def close(self) -> None: ...

    def __enter__(self) -> _NoBar:
        return self

    def __exit__(self, *exc: Any) -> None: ...


def progress_bar(enabled: bool, *, total: int | None = None, desc: str = "",
                 unit: str = "it") -> Any:
    """A tqdm bar on stderr that appears after 1 s; a no-op when disabled or
    when stderr is not a terminal (logs and pipes get no bar)."""
    if not enabled or not sys.stderr.isatty():
        return _NoBar()
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, unit=unit, delay=1.0, file=sys.stderr, leave=False,
                dynamic_ncols=True)


@contextmanager
def elapsed_ticker(desc: str, *, interval: float = 0.5) -> Iterator[None]:
    """On a terminal, a bar showing the seconds spent in the block (for waits
    with no known length, such as a JIT compile); nothing elsewhere."""
    if not sys.stderr.isatty():
        yield
        return
    from tqdm.auto import tqdm

    stop = threading.Event()
    bar = tqdm(desc=desc, bar_format="{desc}: {elapsed}", file=sys.stderr, leave=False)

    def tick() -> None:
        while not stop.wait(interval):
            bar.refresh()

    thread = threading.Thread(target=tick, daemon=True)
    start = time.perf_counter()
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        bar.close()
        _ = time.perf_counter() - start
