"""Holding a link to a live robot until stopped, whatever the transport and whatever is done with it.

:class:`Links` connects through a :class:`~lfdfuse.drive.transport.Transport`, hands each link
to a ``serve`` coroutine, and connects again with back-off when the link is lost, until
``--duration``, a signal (SIGINT/SIGTERM) or :meth:`Stopper.stop`. A run that never connected
is an error. ``drive`` and ``record`` both run on it.
"""

from __future__ import annotations

import asyncio
import signal
import time
from collections.abc import Awaitable, Callable
from contextlib import suppress
from typing import Any

from lfdfuse.drive.options import DriveError, Notify, Stopper
from lfdfuse.drive.transport import Link, Lost, Transport

#: the first connection must open within this (a later one is retried while --duration lasts)
CONNECT_TIMEOUT_S = 3.0
BACKOFF_S = (0.2, 2.0)  # first retry delay, the longest

Serve = Callable[[Link, asyncio.Event], Awaitable[None]]
Warn = Callable[[str, str], None]


class Links:
    """Connect, serve, reconnect (see the module docstring); ``connections`` counts the links
    that opened, ``reconnected`` is called on every one after the first."""

    def __init__(
        self,
        transport: Transport,
        stopper: Stopper,
        *,
        warn: Warn,
        notify: Notify,
        reconnected: Callable[[], None] = lambda: None,
    ) -> None:
        self.transport, self.stopper = transport, stopper
        self.warn, self.notify, self.reconnected = warn, notify, reconnected
        self.connections = 0
        self._unreachable = ""  # why the last attempt to connect failed

    async def run(self, serve: Serve, *, duration_s: float | None) -> str:
        """Serve links until stopped; return why it stopped. The signals' handlers are ours
        while it runs and the caller's again after (the CLI's SIGTERM → clean unwinding)."""
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()
        self.stopper.bind(loop, stop)
        if self.stopper.reason:
            stop.set()
        handlers: dict[signal.Signals, Any] = {}
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                previous = signal.getsignal(sig)
                loop.add_signal_handler(sig, self.stopper.stop, f"signal {sig.name}")
                handlers[sig] = previous
            except (RuntimeError, ValueError, NotImplementedError):
                pass  # not the main thread (a test): stop through the Stopper
        timer = None
        if duration_s is not None:
            timer = loop.call_later(duration_s, self.stopper.stop, "--duration")
        try:
            await self._serve_links(serve, stop)
        finally:
            if timer is not None:
                timer.cancel()
            for sig, previous in handlers.items():
                loop.remove_signal_handler(sig)
                signal.signal(sig, previous)
        return self.stopper.reason or "stopped"

    async def _serve_links(self, serve: Serve, stop: asyncio.Event) -> None:
        url = self.transport.url
        backoff = BACKOFF_S[0]
        first_by = time.monotonic() + CONNECT_TIMEOUT_S
        while not stop.is_set():
            try:
                link = await self.transport.connect(timeout_s=CONNECT_TIMEOUT_S, warn=self.warn)
            except Lost as exc:
                self._unreachable = str(exc)
                if self.connections == 0 and time.monotonic() > first_by:
                    break
            else:
                self.connections += 1
                backoff = BACKOFF_S[0]
                if self.connections > 1:
                    self.notify(f"reconnected to {url}")
                    self.reconnected()
                try:
                    await serve(link, stop)
                except Lost as exc:
                    if not stop.is_set():
                        self.warn(f"lost {self.connections}", f"connection lost ({exc}): reconnecting")
            if stop.is_set():
                break
            with suppress(TimeoutError):  # back off, but wake at once on stop
                await asyncio.wait_for(stop.wait(), timeout=backoff)
            backoff = min(backoff * 2, BACKOFF_S[1])
        if self.connections == 0:
            why = self._unreachable or f"stopped ({self.stopper.reason or 'stopped'}) before it answered"
            raise DriveError(f"cannot connect to {url}: {why}")
