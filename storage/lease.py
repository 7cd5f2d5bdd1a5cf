"""The sweep lease: one sweep per object root, held with a lease object instead of ``flock``.

An object store has no lock that its server drops when the holder dies, so the lock of an
object root is an object, ``<root>/store.lock``, holding JSON ``{"holder", "token",
"expires_s"}`` (``expires_s`` in seconds since the epoch, by the holder's clock):

* **taken** with a conditional PUT that succeeds only if there is no such object
  (``If-None-Match: *``);
* **renewed** by a background thread every third of its duration, with a PUT conditional on
  the ETag the holder last wrote (``If-Match``), so nobody else's lease is ever overwritten;
* **taken over** when found expired, with a PUT conditional on the expired lease's ETag: of two
  sweeps that find it expired at once, one wins;
* **released** by deleting it (after checking it is still ours).

A killed sweep therefore blocks its root until its lease expires (:data:`LEASE_S`, 60 s by
default; ``ESKIN_LEASE_S`` sets it), never longer. Clocks of the machines that share a root must
agree to well within the lease's duration. A holder that cannot renew (its lease was taken
over after it stalled past expiry) stops renewing and warns; its writes are then no longer
exclusive.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import threading
import time
import uuid
import warnings
from collections.abc import Iterator

from storage.errors import StoreBusyError, StoreError, one_line
from storage.locking import LOCK_NAME
from storage.objects import Conflict, Objects

#: Seconds a lease lasts unless renewed (``ESKIN_LEASE_S`` overrides it).
LEASE_S = 60.0

# Leases this process holds: root URL -> [lease, nesting depth].
_HELD: dict[str, list] = {}
_HELD_GUARD = threading.Lock()


def lease_seconds() -> float:
    """The lease duration: ``ESKIN_LEASE_S`` if set (a positive number of seconds), else
    :data:`LEASE_S`."""
    text = os.environ.get("ESKIN_LEASE_S")
    if text is None:
        return LEASE_S
    try:
        seconds = float(text)
    except ValueError:
        seconds = -1.0
    if not seconds > 0:
        raise StoreError(f"ESKIN_LEASE_S={text!r}: expected a positive number of seconds")
    return seconds


@contextlib.contextmanager
def hold_lease(objects: Objects) -> Iterator[None]:
    """Hold the root's lease for the ``with`` block (nesting within one process), renewing it.

    Raises
    ------
    StoreBusyError
        Another sweep holds an unexpired lease; the message names the root and the holder.
    """
    name = objects.url
    with _HELD_GUARD:
        held = _HELD.get(name)
        if held is not None:
            held[1] += 1
        else:
            lease = _Lease(objects, lease_seconds())
            lease.take()
            _HELD[name] = held = [lease, 1]
    try:
        yield
    finally:
        with _HELD_GUARD:
            held[1] -= 1
            if held[1] == 0:
                del _HELD[name]
                held[0].release()


class _Lease:
    def __init__(self, objects: Objects, seconds: float):
        self.objects = objects
        self.seconds = seconds
        self.token = uuid.uuid4().hex
        self.holder = f"PID {os.getpid()} on {socket.gethostname()}"
        self.etag = ""
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._renew, name="eskin-lease", daemon=True)

    def _body(self) -> bytes:
        expires = time.time() + self.seconds
        body = {"holder": self.holder, "token": self.token, "expires_s": expires}
        return json.dumps(body).encode()

    def take(self) -> None:
        try:
            self.etag = self.objects.put_if_absent(LOCK_NAME, self._body())
        except Conflict:
            self._take_over()
        self._thread.start()

    def _take_over(self) -> None:
        """Take an expired lease over; refuse a live one."""
        root = self.objects.url
        try:
            data, etag = self.objects.get(LOCK_NAME)
        except FileNotFoundError:  # released meanwhile: try again from the start
            data, etag = b"{}", ""
        try:
            found = json.loads(data)
            holder, expires = str(found["holder"]), float(found["expires_s"])
        except (ValueError, KeyError, TypeError):
            holder, expires = "unknown", 0.0  # unreadable: as good as expired
        if expires > time.time():
            raise StoreBusyError(
                f"run root {root} is in use by another sweep ({holder[:80]}, its lease ends in "
                f"{expires - time.time():.0f} s unless renewed); wait for it to finish or give "
                "another --root"
            )
        try:
            if etag:
                self.etag = self.objects.put_if_match(LOCK_NAME, self._body(), etag)
            else:
                self.etag = self.objects.put_if_absent(LOCK_NAME, self._body())
        except Conflict:
            raise StoreBusyError(
                f"run root {root} is in use by another sweep (it took the expired lease "
                "first); wait for it to finish or give another --root"
            ) from None

    def _renew(self) -> None:
        while not self._stop.wait(self.seconds / 3):
            try:
                self.etag = self.objects.put_if_match(LOCK_NAME, self._body(), self.etag)
            except Conflict:
                warnings.warn(
                    f"the lease of run root {self.objects.url} was taken over by another sweep; "
                    "this sweep's writes are no longer exclusive",
                    RuntimeWarning,
                    stacklevel=1,
                )
                return
            except (StoreError, OSError) as error:  # a passing outage: try again next round
                warnings.warn(
                    f"could not renew the lease of {self.objects.url}: {one_line(error)}",
                    RuntimeWarning,
                    stacklevel=1,
                )

    def release(self) -> None:
        self._stop.set()
        self._thread.join()
        with contextlib.suppress(FileNotFoundError, StoreError, OSError):
            data, _ = self.objects.get(LOCK_NAME)
            if json.loads(data).get("token") == self.token:
                self.objects.delete([LOCK_NAME])
