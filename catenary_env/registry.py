"""A registry: a dict of named entries that refuses to replace one (the problems' and the optimisers').

Examples
--------
>>> from typing import NamedTuple
>>> class Entry(NamedTuple):
...     name: str
>>> registry = Registry[Entry]()
>>> registry["a"] = Entry("a")
>>> registry["a"] = Entry("a")
Traceback (most recent call last):
...
ValueError: entry 'a' is already registered
"""

from __future__ import annotations

from typing import Any, ClassVar, Protocol, Self, TypeVar

__all__ = ["Named", "Registry"]


class Named(Protocol):
    """An entry of a registry: known by its name."""

    @property
    def name(self) -> str: ...


T = TypeVar("T", bound=Named)


class Registry(dict[str, T]):
    """Entries by name: a dict that refuses to replace an entry, or to file one under another name.

    A subclass sets :attr:`kind`, the word its messages use (``"design problem"``, ``"optimizer"``).
    """

    kind: ClassVar[str] = "entry"

    def __setitem__(self, name: str, entry: T) -> None:
        if name in self:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        if name != entry.name:
            raise ValueError(f"{self.kind} registered as {name!r} is named {entry.name!r}")
        super().__setitem__(name, entry)

    def register(self, entry: T) -> T:
        """File ``entry`` under its name and return it; ValueError if the name is taken."""
        self[entry.name] = entry
        return entry

    def update(self, *args: Any, **kwargs: T) -> None:  # type: ignore[override]
        # dict.update bypasses __setitem__: route it through the check.
        for name, entry in dict(*args, **kwargs).items():
            self[name] = entry

    def setdefault(self, name: str, entry: T) -> T:  # type: ignore[override]
        if name not in self:
            self[name] = entry
        return self[name]

    def __ior__(self, other: Any) -> Self:  # type: ignore[override, misc]
        self.update(other)
        return self
