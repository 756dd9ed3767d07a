"""Keeping a browser-rendered (vtk.js) view in step with its scene in the kernel.

:class:`BrowserDraws` paces the changes sent to the browser by the pictures it has drawn;
:func:`send_changes_only` makes a trame ``VtkLocalView`` send each render as a change only.
"""

from __future__ import annotations

import asyncio
import collections
import time
import weakref
from collections.abc import Callable
from typing import Any, Protocol

#: a function that runs ``fn()`` in ``delay`` seconds without blocking
CallLater = Callable[[float, Callable[[], None]], object]


class BrowserDraws:
    """Changes sent to a browser-rendered (vtk.js) view and not yet drawn there.

    The view answers every change it has applied (its ``afterSceneLoaded`` event, a message
    back to the kernel). So the kernel sends a change only once the last one is drawn, and
    while the browser draws it keeps only the newest (:meth:`send_or_wait`): a drag faster
    than the browser draws shows its latest state, never a backlog; a player waits for the
    picture on the student's screen, not only on the network, and its frame skip says what is
    seen. Until a first answer arrives nothing is waited for (a view that never answers), and
    a change unanswered after ``patience`` seconds is forgotten (a closed tab, a lost message).

    Parameters
    ----------
    patience : seconds after which an unanswered change is forgotten.
    clock : the time in seconds (default :func:`time.monotonic`).
    call_later : runs a function later (default: the kernel's event loop).
    """

    def __init__(self, *, patience: float = 1.0, clock: Callable[[], float] | None = None,
                 call_later: CallLater | None = None) -> None:
        self.patience = float(patience)
        self.clock = clock or time.monotonic
        self.call_later = call_later or event_loop_call_later
        self._sent: collections.deque[float] = collections.deque()
        self._waiting: Callable[[], None] | None = None  # the newest change held back
        self.answers = False  # the browser has answered at least once
        self.count = 0  # changes drawn, as the browser said

    def pending(self) -> int:
        """Changes sent and not yet drawn (0 while the browser has never answered)."""
        now = self.clock()
        while self._sent and now - self._sent[0] > self.patience:
            self._sent.popleft()
        return len(self._sent) if self.answers else 0

    def send_or_wait(self, send: Callable[[], None]) -> None:
        """Call ``send`` (which sends the scene's changes) now if the browser has drawn all it
        was sent, else once it has (only the newest ``send`` is kept)."""
        if not self.pending():
            self._send(send)
            return
        if self._waiting is None:  # a browser that stops answering is waited for no longer
            self.call_later(self.patience, self._send_waiting)
        self._waiting = send

    def drawn(self, *_event: object) -> None:
        """The browser has applied a change and draws it (the oldest one sent)."""
        self.answers = True
        self.count += 1
        if self._sent:
            self._sent.popleft()
        if not self.pending():
            self._send_waiting()

    def _send(self, send: Callable[[], None]) -> None:
        self._sent.append(self.clock())
        send()

    def _send_waiting(self) -> None:
        send, self._waiting = self._waiting, None
        if send is not None:
            self._send(send)


def event_loop_call_later(delay: float, fn: Callable[[], None]) -> None:
    """Run ``fn()`` in ``delay`` seconds on the running event loop (the kernel's)."""
    asyncio.get_event_loop().call_later(delay, fn)


class SceneHelper(Protocol):
    """trame-vtk's serializer of a render window (a ``VtkLocalView``'s ``module``)."""

    def scene(self, render_window: Any, new_state: bool, widgets: list[Any],
              orientation_axis: int) -> dict[str, Any]: ...


class LocalView(Protocol):
    """What :func:`send_changes_only` uses of trame-vtk's ``VtkLocalView``."""

    # trame's server; its ``protocol`` publishes to the page, None before the page connects
    server: Any
    update: Callable[..., None]

    @property
    def module(self) -> SceneHelper: ...

    def get_widgets(self) -> list[Any]: ...


def send_changes_only(view: LocalView, render_window: object, draws: BrowserDraws) -> None:
    """Make a browser-rendered (vtk.js) view of ``render_window`` send only what changed on
    each render.

    trame's ``VtkLocalView.update`` serializes the scene twice per render: the changes
    (published at once) and the whole state (kept for a page that reloads), which the browser
    then applies a second time; trame offers no option to send the changes alone. Here a
    render publishes the changes only, paced by the browser's draws (``draws``, see
    :class:`BrowserDraws`); the whole state is refreshed once the view has been still for a
    second. Until a page has shown the scene (its first answer) every render keeps the whole
    state: a page loads that state once, when it opens, and takes only changes afterwards, so
    a state older than the page would stay on it.

    This replaces the view's ``update`` with one built from the same public calls trame's
    makes (``module.scene`` and the ``trame.vtk.delta`` topic), as in trame-vtk 2.11.17.
    """
    full_update = view.update
    helper = view.module
    last = [0.0, False]  # time of the last change, whether a refresh is scheduled

    def refresh() -> None:  # one timer per quiet second, not one per render
        wait = last[0] + 1.0 - draws.clock()
        if wait > 0:
            draws.call_later(wait, refresh)
            return
        last[1] = False
        full_update()

    def update(widgets: list[Any] | None = None, orientation_axis: int = 0,
               **_kwargs: object) -> None:
        def send() -> None:  # the scene as it is when sent: the newest state
            protocol = view.server.protocol
            if not protocol:
                return
            delta = helper.scene(render_window, new_state=False,
                                 widgets=view.get_widgets() if widgets is None else widgets,
                                 orientation_axis=orientation_axis)
            protocol.publish("trame.vtk.delta", delta)
            last[0] = draws.clock()
            if not last[1]:
                last[1] = True
                draws.call_later(1.0, refresh)

        if not draws.answers:  # no page has shown the scene yet: it will load the whole of it
            full_update(widgets=widgets, orientation_axis=orientation_axis)
            return
        draws.send_or_wait(send)

    view.update = update


def keep_scene_arrays(view: LocalView) -> None:
    """Keep, in the kernel, every data array of the scene a page of ``view``'s trame server
    loads when it opens, however late it opens.

    A page shows a scene in two steps: it reads the scene's state (a ``scene_<ref>`` entry of
    the server's state, the arrays named by their hashes) and then fetches each array from
    the kernel's cache. trame-vtk (2.11) drops from that cache, at every render of any view,
    the arrays that nothing else holds and that were cached over 20 s ago, and the cell
    arrays (converted on the way) are held by nothing else. So a page that fetches later,
    e.g. a view far down a notebook run with "Run All" while the kernel was busy, or an
    off-screen view the browser throttles, finds its arrays gone and never draws. Here the
    arrays of the scene states of the views passed count as used at each such check: they stay
    while a page can still ask for them, and an array no scene names any more goes as before
    (the cache stays bounded)."""
    # the state entry trame-vtk's VtkLocalView keeps its scene in ("scene_<ref>")
    key = getattr(view, "_VtkLocalView__scene_id", None)
    protocol = getattr(view.module, "_root_protocol", None)
    if key is None or protocol is None:
        return
    server = view.server
    if server not in _SCENES:
        for link in protocol.getLinkProtocols():
            context = getattr(link, "context", None)
            if context is not None and hasattr(context, "check_for_arrays_to_release"):
                _SCENES[server] = set()
                _pin_scene_arrays(context, server.state, _SCENES[server])
    if server in _SCENES:
        _SCENES[server].add(key)


# the trame servers whose array caches keep scenes, and the state entries of those scenes
_SCENES: weakref.WeakKeyDictionary[Any, set[str]] = weakref.WeakKeyDictionary()


def _pin_scene_arrays(context: Any, state: Any, keys: set[str]) -> None:
    """Wrap ``context.check_for_arrays_to_release`` (see :func:`keep_scene_arrays`): the
    arrays of the scenes in ``state`` under ``keys`` count as used now. (Read entry by
    entry: ``state.to_dict()`` would flush, sending whole scenes to pages that take only
    changes, see :func:`send_changes_only`.)"""
    from trame_vtk.modules.vtk.serializers import extract_array_hash

    release = context.check_for_arrays_to_release
    hashes: dict[str, tuple[int, list[str]]] = {}  # scene key -> (id of its state, hashes)

    def check(time_window: float = 20, **kwargs: Any) -> None:
        now = time.time()
        for key in keys:
            scene = state[key]
            if not scene:
                continue
            if key not in hashes or hashes[key][0] != id(scene):
                hashes[key] = (id(scene), [e["hash"] for e in extract_array_hash(scene)])
            for h in hashes[key][1]:
                record = context.data_array_cache.get(h)
                if record is not None:
                    record["ts"] = now
        release(time_window, **kwargs)

    context.check_for_arrays_to_release = check
