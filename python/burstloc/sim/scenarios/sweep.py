"""Map a function over items in parallel, with a progress bar and per-item errors.

:func:`sweep` runs ``func(item)`` for every item:

* in this process, one after the other, when ``workers == 1`` (or there is a single item);
* in local worker processes (``concurrent.futures`` with the ``spawn`` start method) by
  default, ``workers`` of them (default: the number of CPUs);
* on a Dask cluster when ``scheduler`` gives its address (``tcp://host:8786``).

A failing item does not stop the others: its exception is reported in
:attr:`SweepReport.failures` with the item, and every other item completes. ``func`` and the
items must be picklable for the parallel modes (a module-level function, plain data).
"""

from __future__ import annotations

import gc
import itertools
import os
import signal
import sys
import threading
import traceback
import uuid
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass, field
from multiprocessing import active_children, get_context
from typing import Any, Generic, TypeVar

from tqdm.auto import tqdm

from burstloc.exceptions import ConfigError

__all__ = ["ItemFailure", "SweepReport", "check_scheduler", "sweep"]

T = TypeVar("T")
R = TypeVar("R")

#: Items submitted to local workers beyond one each, ready for the next worker to be free.
QUEUED = 1

#: Seconds to wait for a Dask scheduler to answer.
DASK_CONNECT_TIMEOUT = 10.0


@dataclass(frozen=True)
class ItemFailure(Generic[T]):
    """One item whose function call raised.

    Attributes:
        index: position of the item in the input.
        item: the item.
        label: how the item is named in messages (e.g. ``"pipe 7"``).
        error_type: the exception's class name.
        message: the exception's message.
        traceback: the formatted traceback (from the worker, when there is one).
    """

    index: int
    item: T
    label: str
    error_type: str
    message: str
    traceback: str

    def __str__(self) -> str:
        return f"{self.label}: {self.error_type}: {self.message}"

    @classmethod
    def from_exception(cls, index: int, item: T, label: str, exc: BaseException) -> ItemFailure[T]:
        """Record ``exc`` raised for ``item``."""
        text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
        return cls(index, item, label, type(exc).__name__, str(exc), text)


@dataclass
class SweepReport(Generic[T, R]):
    """What a sweep produced: ``results[i]`` is ``func(items[i])``, or ``None`` if it failed."""

    items: list[T]
    results: list[R | None]
    failures: list[ItemFailure[T]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when every item succeeded."""
        return not self.failures

    def failure_lines(self) -> list[str]:
        """The failures, one line per distinct error: ``"pipes 1, 2 and 3 of N: Type:
        message"`` (a network that cannot be simulated fails every pipe the same way: said
        once, not once per pipe)."""
        groups: dict[tuple[str, str], list[str]] = {}
        for failure in self.failures:
            groups.setdefault((failure.error_type, failure.message), []).append(failure.label)
        lines = []
        for (kind, message), labels in groups.items():
            if len(labels) == 1:
                lines.append(f"{labels[0]}: {kind}: {message}")
                continue
            listed = ", ".join(labels[:5]) + (
                f" and {len(labels) - 5} more" if len(labels) > 5 else ""
            )
            lines.append(f"{len(labels)} of {len(self.items)} ({listed}): {kind}: {message}")
        return lines

    def succeeded(self) -> list[tuple[T, R]]:
        """Return ``(item, result)`` for the items that succeeded, in input order."""
        failed = {f.index for f in self.failures}
        return [
            (item, result)
            for i, (item, result) in enumerate(zip(self.items, self.results, strict=True))
            if i not in failed and result is not None
        ]


def sweep(
    func: Callable[[T], R],
    items: Iterable[T],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    desc: str = "",
    label: Callable[[T], str] = repr,
    on_result: Callable[[int, T, R], None] | None = None,
    keep: bool = True,
) -> SweepReport[T, R]:
    """Run ``func`` over ``items`` and report results and failures.

    Args:
        func: called once per item (in a worker process or Dask worker in parallel modes).
        items: the inputs.
        workers: local worker processes (default: CPU count); 1 runs in this process.
            Ignored when ``scheduler`` is given.
        scheduler: a Dask scheduler address; runs the items as Dask tasks there.
        progress: show a tqdm progress bar on stderr.
        desc: the progress bar's label.
        label: names an item in failure messages.
        on_result: called in this process as each item succeeds, ``(index, item, result)``
            (e.g. to store it in a cache as soon as it exists).
        keep: hold every result in the report; ``False`` leaves the report's results ``None``
            (results only handed to ``on_result``, e.g. reduced there as they arrive).

    Raises:
        ConfigError: ``workers`` is not a positive integer, or the scheduler cannot be reached.
    """
    todo = list(items)
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ConfigError(f"workers must be a positive integer, got {workers!r}")
    report: SweepReport[T, R] = SweepReport(todo, [None] * len(todo))
    if not todo:
        return report
    bar = tqdm(total=len(todo), desc=desc or None, disable=not progress, file=sys.stderr)

    def done(index: int, result: R | None, exc: BaseException | None) -> None:
        if exc is not None:
            report.failures.append(
                ItemFailure.from_exception(index, todo[index], label(todo[index]), exc)
            )
        else:
            if keep:
                report.results[index] = result
            if on_result is not None:
                on_result(index, todo[index], result)  # type: ignore[arg-type]
        bar.update(1)

    try:
        if scheduler is not None:
            _run_dask(func, todo, scheduler, done)
        elif (workers or os.cpu_count() or 1) == 1 or len(todo) == 1:
            with _sigint_remembered() as interrupted:
                for index, item in enumerate(todo):
                    try:
                        result = func(item)
                    except Exception as exc:
                        done(index, None, exc)
                    else:
                        done(index, result, None)
                    if interrupted:  # swallowed inside ``func`` (TSNet's bare ``except:``)
                        raise KeyboardInterrupt
        else:
            _run_processes(func, todo, min(workers or os.cpu_count() or 1, len(todo)), done)
    finally:
        bar.close()
    report.failures.sort(key=lambda f: f.index)
    return report


_Done = Callable[[int, R | None, BaseException | None], None]


def _ignore_interrupts() -> None:
    """Worker initializer: Ctrl-C (SIGINT to the whole process group) is the parent's to handle.

    A worker starts with SIGINT blocked (see :func:`_run_processes`): one that arrived while it
    started stays pending, and is discarded here, once ignored.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


@contextmanager
def _sigint_remembered() -> Iterator[list[int]]:
    """Ctrl-C raises ``KeyboardInterrupt`` as usual, and is also recorded in the yielded list,
    so that the caller can stop after an item whose code swallowed the exception (TSNet's
    solver catches everything with bare ``except:`` clauses)."""
    interrupted: list[int] = []
    main = threading.current_thread() is threading.main_thread()
    if not main or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield interrupted  # signals are the main thread's; a caller's own handling stands
        return

    def remember(signum: int, frame: object) -> None:
        interrupted.append(signum)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, remember)
    try:
        yield interrupted
    finally:
        signal.signal(signal.SIGINT, previous)


@contextmanager
def _sigint_deferred() -> Iterator[None]:
    """Hold Ctrl-C back for the ``with`` block, then raise it (``KeyboardInterrupt``) at its end.

    SIGINT is blocked in this thread, so the processes started in the block inherit a blocked
    SIGINT; and one delivered meanwhile (to another thread) is only recorded, so that no process
    is left half-started by an interrupt.
    """
    if threading.current_thread() is not threading.main_thread():
        yield  # signals are the main thread's: nothing to hold back here
        return
    interrupted: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: interrupted.append(signum))
    blockable = hasattr(signal, "pthread_sigmask")
    if blockable:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        if blockable:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
        signal.signal(signal.SIGINT, previous)
    if interrupted:
        raise KeyboardInterrupt


def _run_processes(func: Callable[[T], R], todo: list[T], workers: int, done: _Done) -> None:
    """Run ``todo`` on ``workers`` spawned processes, at most ``workers +`` :data:`QUEUED` items
    submitted and not yet handed to ``done``: a parent slower to take results (an evaluation
    scoring each burst) than its workers are to make them would otherwise hold every result
    made meanwhile (on L-TOWN 200 MB each). On Ctrl-C (or any error of the parent) the pending
    items are cancelled and the workers stopped at once, then the error goes on."""
    pool = ProcessPoolExecutor(
        max_workers=workers, mp_context=get_context("spawn"), initializer=_ignore_interrupts
    )
    items = iter(enumerate(todo))
    futures: dict[Future[R], int] = {}

    def submit(count: int) -> None:
        for i, item in itertools.islice(items, count):
            futures[pool.submit(func, item)] = i

    try:
        # The workers start while the first items are submitted: a Ctrl-C then waits for the
        # end of those submissions here, and for their initializer (which ignores it) in the
        # workers.
        with _sigint_deferred():
            submit(workers + QUEUED)
        while futures:
            finished = wait(futures, return_when=FIRST_COMPLETED).done
            while finished:
                # popped from both: a future holds its result, which ``done`` may let go of
                future = finished.pop()
                exc = future.exception()
                done(futures.pop(future), None if exc else future.result(), exc)
                del future
                submit(1)
    except BaseException:
        # Workers stopped first: the pool's own thread then sees them gone, fails what is
        # pending and ends, and the shutdown waits for it and frees the pool's queues here.
        # (A shutdown without waiting would leave that thread, and the queues' semaphores, to
        # the end of the process, and Python's resource tracker would warn of them after the
        # run's last line.)
        children = active_children()
        for child in children:
            child.terminate()
        for child in children:
            child.join()
        pool.shutdown(wait=True, cancel_futures=True)
        del pool
        gc.collect()
        raise
    pool.shutdown()


def _connect(scheduler: str) -> Any:
    """A Dask client of ``scheduler`` (ConfigError when it cannot be reached)."""
    from dask.distributed import Client

    try:
        return Client(scheduler, timeout=DASK_CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from exc


def check_scheduler(scheduler: str) -> None:
    """Connect to the Dask scheduler at ``scheduler`` and disconnect: a command checks the
    address before any work, even when nothing will run there (every result cached).

    Raises:
        ConfigError: the scheduler cannot be reached within :data:`DASK_CONNECT_TIMEOUT` s.
    """
    _connect(scheduler).close()


def _run_dask(func: Callable[[T], R], todo: list[T], scheduler: str, done: _Done) -> None:
    from dask.distributed import as_completed as dask_completed

    client = _connect(scheduler)
    try:
        run = uuid.uuid4().hex[:8]
        futures = [
            client.submit(func, item, key=f"burstloc-{run}-{i}", pure=False)
            for i, item in enumerate(todo)
        ]
        index = {future.key: i for i, future in enumerate(futures)}
        for future in dask_completed(futures, loop=client.loop):
            if future.status == "error":
                done(index[future.key], None, future.exception())
            else:
                done(index[future.key], future.result(), None)
            future.release()
    finally:
        client.close()
