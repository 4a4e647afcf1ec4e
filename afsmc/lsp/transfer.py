"""A job's message sent from its child process to the language server in parts, each a pickle
of its own that is decoded in the server's decoding thread without holding the interpreter's
lock for long (worker.py).

Why parts: an unpickler keeps every object it made in its memo, and lets the memo go in one
step when it is freed: for the parse of a big document (millions of objects) that one step
held the interpreter's lock, and with it the event loop's thread, long enough to delay a
request on another document. Cut into parts, each unpickler's memo holds the objects of one
part only, however big the document.

How: every list, tuple or dict of more than PART_ITEMS items (in the message itself, or a
field of an object in it) is sent as parts of PART_ITEMS items each, before the rest of the
message (the last part) that refers to them. The receiver keeps the items of each part in
a table; the last part names a container by its ranges of that table, and an object that
is an item of an earlier part (a declaration that both the module and the index hold) by
its place there, so it is not sent twice. A `Source` (the whole text, which every span
refers to) goes in a part of its own the first time it is met, and by its place after.
"""

from __future__ import annotations

import copyreg
import gc
import io
import pickle
import re
import traceback
from collections.abc import Callable
from typing import Any

from afsmc.diagnostics import Source
from afsmc.heap import collector_paused

PART_ITEMS = 1000  # the items of a big container sent per part
_CONTAINERS = frozenset((list, tuple, dict))


def _big(value: Any) -> bool:
    return type(value) in _CONTAINERS and len(value) > PART_ITEMS


class _Later:
    """A big container in what is being pickled: cut into parts when the pickler comes to
    it (not before), so that its parts follow the parts of whatever was pickled before it,
    which its items may refer to."""

    def __init__(self, value: list[Any] | tuple[Any, ...] | dict[Any, Any]) -> None:
        self.value = value


def shared(k: int) -> Any:
    """In a pickle: the item at place `k` of the receiver's table (_Unpickler.find_class
    gives the table's own lookup instead of this)."""
    raise RuntimeError("a message part's reference decoded outside its message")


def joined(kind: str, ranges: tuple[tuple[int, int], ...]) -> Any:
    """In a pickle: a container made of the receiver's table at `ranges` (see
    _Unpickler.find_class)."""
    raise RuntimeError("a message part's container decoded outside its message")


class _Pickler(pickle.Pickler):
    """A pickler of one part. Objects of the types in `parts.reductions` (those that may be
    an item of an earlier part, hold a big container, or be the text) go through
    `parts.reduce`; every other object is pickled as pickle does, without a call into
    Python (a call per object made a big document's parse twice as slow to send)."""

    def __init__(self, file: io.BytesIO, parts: Parts) -> None:
        self.dispatch_table = parts.reductions  # (read by pickle's __init__)
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)


_WATCH: dict[type, Any] = {_Later: _Later, Source: Source}
_NEWOBJ: Callable[..., Any] = vars(copyreg)["__newobj__"]  # how pickle makes an object
_OWN_REDUCTION = ("__reduce_ex__", "__reduce__", "__getstate__")
_CONTAINER_TYPE = re.compile(r"\b(?:tuple|list|dict|Tuple|List|Dict|Any|object)\b")


def _watched(cls: type) -> Any:
    """What `Parts.reduce` looks at in an object of `cls`: _Later or Source for those;
    for a dataclass, the names of its fields that may hold a container (typed `tuple[...]`,
    `list[...]`, `dict[...]`, `Any` or `object`); None for every other class (pickled as
    pickle does), for a dataclass without such a field, and for one that reduces itself."""
    if cls in _WATCH:
        return _WATCH[cls]
    fields = getattr(cls, "__dataclass_fields__", None)
    watch = None
    if (fields is not None and not hasattr(cls, "__slots__")
            and all(getattr(cls, m) is vars(object)[m] for m in _OWN_REDUCTION)):
        watch = tuple(name for name, f in fields.items()
                      if _CONTAINER_TYPE.search(str(f.type))) or None
    _WATCH[cls] = watch
    return watch


class Parts:
    """The parts of one message, made in the child process."""

    def __init__(self) -> None:
        self.out: list[bytes] = []  # the parts so far, in the order they are sent
        self.slot: dict[int, int] = {}  # id of an object of an earlier part -> its place
        self._keep: list[Any] = []  # those objects, kept alive so that their ids stay theirs
        self._size = 0  # places in the receiver's table so far
        self._alone: object = None  # the Source whose own part is being made
        # the types whose objects go through `reduce` (a pickler's dispatch table)
        self.reductions: dict[type, Callable[[Any], Any]] = {
            _Later: self.reduce, Source: self.reduce}

    def encode(self, msg: Any) -> list[bytes]:
        """Every part of `msg`: the last one is the message itself."""
        self._owners(msg)
        last = self._dump(self._top(msg))
        return [*self.out, last]

    def _owners(self, msg: Any) -> None:
        """Put in `reductions` the types of the objects of `msg`'s frame that hold a big
        container: the objects reached from it through tuples and fields that are not
        containers. (An item of a big container that holds one is found when its container
        is cut.)"""
        todo, seen = [msg], set()
        while todo:
            obj = todo.pop()
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            if type(obj) is tuple and not _big(obj):
                todo += obj
                continue
            watch = _watched(type(obj))
            if type(watch) is not tuple and not hasattr(obj, "__dataclass_fields__"):
                continue
            state = getattr(obj, "__dict__", {})
            if type(watch) is tuple and any(_big(state.get(name)) for name in watch):
                self.reductions[type(obj)] = self.reduce
            todo += [v for v in state.values() if hasattr(v, "__dataclass_fields__")]

    def reduce(self, obj: Any) -> Any:
        """How an object of a type in `reductions` is pickled: by its place if an earlier
        part holds it; a big container cut into parts; the text in a part of its own the
        first time; an object with a big container with that container marked to be cut
        (`_Later`); any other as pickle would."""
        k = self.slot.get(id(obj))
        if k is not None:
            return shared, (k,)
        cls = type(obj)
        if cls is _Later:
            return self.cut(obj.value)
        if cls is Source and obj is not self._alone:
            self.alone(obj)
            return shared, (self.slot[id(obj)],)
        watch = _watched(cls)
        names: tuple[str, ...] = watch if type(watch) is tuple else ()
        state = obj.__dict__ if names else {}
        if not any(_big(state.get(name)) for name in names):
            return obj.__reduce_ex__(pickle.HIGHEST_PROTOCOL)
        return (_NEWOBJ, (cls,), {name: _Later(v) if _big(v) else v for name, v in state.items()})

    def _top(self, value: Any) -> Any:
        if type(value) is tuple and not _big(value):
            return tuple(self._top(v) for v in value)
        return _Later(value) if _big(value) else value

    def _dump(self, obj: Any) -> bytes:
        f = io.BytesIO()
        _Pickler(f, self).dump(obj)
        return f.getvalue()

    def _add(self, items: list[Any], data: bytes) -> tuple[int, int]:
        """`items` sent as the next part: their places in the receiver's table."""
        start = self._size
        for j, item in enumerate(items):
            self.slot[id(item)] = start + j
            if type(item) not in self.reductions and hasattr(type(item), "__dataclass_fields__"):
                self.reductions[type(item)] = self.reduce  # (it may be referred to later)
        self._keep.append(items)
        self._size += len(items)
        self.out.append(data)
        return start, self._size

    def alone(self, obj: Any) -> None:
        """`obj` in a part of its own."""
        outer, self._alone = self._alone, obj
        try:
            data = self._dump([obj])
        finally:
            self._alone = outer
        self._add([obj], data)

    def cut(self, value: list[Any] | tuple[Any, ...] | dict[Any, Any]
            ) -> tuple[Callable[..., Any], tuple[str, tuple[tuple[int, int], ...]]]:
        """A big container as parts of PART_ITEMS items (a dict's as (key, value) pairs),
        and how the last part names it."""
        items: list[Any] = list(value.items()) if type(value) is dict else list(value)
        ranges = []
        for i in range(0, len(items), PART_ITEMS):
            chunk = items[i:i + PART_ITEMS]
            ranges.append(self._add(chunk, self._dump(chunk)))
        return joined, (type(value).__name__, tuple(ranges))


class _Unpickler(pickle.Unpickler):
    def __init__(self, file: Any, decoder: Decoder) -> None:
        super().__init__(file)
        self._decoder = decoder

    def find_class(self, module: str, name: str) -> Any:
        if module == __name__ and name == "shared":
            return self._decoder.table.__getitem__
        if module == __name__ and name == "joined":
            return self._decoder.joined
        return super().find_class(module, name)


class Frames:
    """A pickle's bytes read through Python methods: the unpickler calls `read` once per
    frame (64 KB), and a Python call is where the interpreter lets another thread run.
    Unpickling from the bytes at once makes the objects of frozen dataclasses in C
    throughout, holding the interpreter's lock, and the event loop's thread waits."""

    def __init__(self, data: bytes) -> None:
        self._data = io.BytesIO(data)

    def read(self, n: int = -1) -> bytes:
        return self._data.read(n)

    def readinto(self, buf: Any) -> int:
        return self._data.readinto(buf)

    def readline(self) -> bytes:
        return self._data.readline()


class Failed:
    """The message a job sends when its work raised: the traceback, for the server's log."""

    def __init__(self, trace: str) -> None:
        self.trace = trace


class Decoder:
    """The receiving end of one job's messages, in the server's decoding thread: `part`
    for each part but the last, `last` for the last, which gives the message.

    The collector is paused while a part is decoded: unpickling makes millions of objects
    and frees none, and the collections that would trigger (each scanning the growing heap,
    holding the interpreter's lock) made decoding five times slower. What the message made
    is then put out of the collector's reach (`gc.freeze`): the analysis of a big document
    is millions of objects without cycles (freed by their reference counts when the
    document changes or closes), and each full collection that scanned them would hold up
    the event loop."""

    def __init__(self) -> None:
        self.table: list[Any] = []
        self._failed: Failed | None = None

    def _load(self, data: bytes) -> Any:
        with collector_paused():
            return _Unpickler(Frames(data), self).load()

    def part(self, data: bytes) -> None:
        if self._failed is not None:
            return
        try:
            self.table.extend(self._load(data))
        except Exception:
            self._failed = Failed(traceback.format_exc())

    def last(self, data: bytes) -> Any:
        try:
            if self._failed is not None:
                return self._failed
            msg = self._load(data)
            gc.freeze()
            return msg
        except Exception:
            return Failed(traceback.format_exc())
        finally:
            self._failed = None
            self._drop()

    def _drop(self) -> None:
        """Let the table go a part at a time (at once, its items' references would be
        dropped in one step)."""
        while self.table:
            del self.table[-PART_ITEMS:]

    def joined(self, kind: str, ranges: tuple[tuple[int, int], ...]) -> Any:
        if kind == "dict":
            out: dict[Any, Any] = {}
            for a, b in ranges:
                out.update(self.table[a:b])
            return out
        items: list[Any] = []
        for a, b in ranges:
            items.extend(self.table[a:b])
        return tuple(items) if kind == "tuple" else items


def let_go(held: list[Any]) -> None:
    """Free what `held` holds (a document's index and model that a newer analysis
    replaced), a part at a time: freed at once, the millions of objects of a big
    document's parse go in one step that holds the interpreter's lock. Run it in the
    decoding thread, and let `held` be the only holder. The items of
    every big container in them (found as `Parts` finds them) are kept aside first, so
    that dropping the containers frees none of them; then they are dropped PART_ITEMS
    at a time."""
    roots = [x for x in held if x is not None]
    held.clear()
    items: list[Any] = []
    todo, obj = list(roots), None
    while todo:
        obj = todo.pop()
        watch = _watched(type(obj))
        if type(watch) is not tuple:
            continue
        for name in watch:
            value = obj.__dict__.get(name)
            if _big(value):
                inner = list(value.values()) if type(value) is dict else list(value)
                items += inner
                todo += inner
    del roots, todo, obj
    while items:
        del items[-PART_ITEMS:]
