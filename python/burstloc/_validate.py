"""Checked reading of the JSON documents burstloc reads (configurations, localization models,
signature sets): one reader, errors that name the file and the field.

* :func:`read_json` reads a file as strict JSON: at most :data:`MAX_JSON_BYTES`, UTF-8, no
  ``NaN``/``Infinity`` (a :class:`~burstloc.exceptions.ConfigError` naming the file and, for a
  non-finite number, the field: :func:`find_non_finite`, which the writer uses too).
* :class:`Fields` walks one JSON object: required fields, nested objects and lists of objects,
  each error naming the file and the field's path (``intervals[0].cusum.threshold``), and
  :meth:`Fields.checking` names them in the errors of the checks a constructor runs.
* :func:`read_npz` reads the binary companion of a document (large matrices, NumPy's ``.npz``,
  never pickled objects): each array present, of the expected kind and rank, floats finite.
* :func:`check_number`, :func:`check_count`, :func:`check_names`, :func:`check_string`: the
  type and range checks themselves (a :class:`FieldError` naming the field), used by the classes
  that validate at construction, so each range is written once, where the class is.
"""

from __future__ import annotations

import contextlib
import json
import math
import numbers
import os
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import Any, TypeVar

import numpy as np

from burstloc.exceptions import ConfigError

T = TypeVar("T")

__all__ = [
    "LISTED",
    "MAX_JSON_BYTES",
    "FieldError",
    "Fields",
    "attributes",
    "check_count",
    "check_names",
    "check_number",
    "check_string",
    "find_non_finite",
    "read_json",
    "read_json_npz",
    "read_npz",
    "read_text",
    "some_names",
]

#: The largest JSON file burstloc reads (bytes): far above any configuration it writes.
MAX_JSON_BYTES = 256 * 1024 * 1024

#: A JSON document's ``.npz`` form (:func:`burstloc._atomic.write_json_npz`): the array holding
#: the document's text, the key marking a list stored as an array, and the fewest numbers a list
#: holds to be stored as one.
NPZ_DOCUMENT = "document"
NPZ_REFERENCE = "$npz"
NPZ_MIN_SIZE = 1024


def read_text(
    path: str | os.PathLike[str], what: str, max_bytes: int = MAX_JSON_BYTES, bom: bool = False
) -> str:
    """Read ``path`` as UTF-8 text of at most ``max_bytes`` (with ``bom``, a leading byte-order
    mark is dropped, as spreadsheets write one).

    Raises:
        ConfigError: the file cannot be read, is too large or is not UTF-8; the message names
            ``what`` and the file.
    """
    where = f"{what} {os.fspath(path)}"
    try:
        with open(path, "rb") as fh:
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise ConfigError(f"cannot read {where}: {exc.strerror or exc}") from None
    if len(data) > max_bytes:
        raise ConfigError(f"cannot read {where}: larger than {max_bytes} bytes")
    try:
        return data.decode("utf-8-sig" if bom else "utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"cannot read {where}: not UTF-8 text (byte {exc.start})") from None


def read_json(path: str | os.PathLike[str], what: str) -> Any:
    """Read ``path`` as strict JSON (UTF-8, no NaN or infinity, at most :data:`MAX_JSON_BYTES`).

    Raises:
        ConfigError: the file cannot be read, is too large, is not UTF-8 or not strict JSON;
            the message names ``what`` and the file.
    """
    return _loads(read_text(path, what), f"{what} {os.fspath(path)}")


def read_npz(
    path: str | os.PathLike[str], what: str, arrays: Mapping[str, tuple[str, int]]
) -> dict[str, np.ndarray]:
    """Read the ``.npz`` file ``path``: ``arrays`` maps each required array's name to its kind
    (``"f"`` float, ``"U"`` text, ``"i"`` integer: NumPy's dtype kinds) and its number of
    dimensions. No pickled object is ever loaded; float arrays must be finite; other arrays in
    the file are ignored.

    Raises:
        ConfigError: the file cannot be read or is not an ``.npz`` file, or an array is missing,
            of another kind or rank, or holds NaN or an infinite value; the message names
            ``what``, the file and the array.
    """
    import zipfile

    where = f"{what} {os.fspath(path)}"
    try:
        if os.path.getsize(path) > MAX_JSON_BYTES * 8:
            raise ConfigError(f"cannot read {where}: larger than {MAX_JSON_BYTES * 8} bytes")
        with np.load(path, allow_pickle=False) as data:
            missing = [name for name in arrays if name not in data.files]
            if missing:
                raise ConfigError(f"{where}: no array {missing[0]!r}")
            found = {name: data[name] for name in arrays}
    except OSError as exc:
        raise ConfigError(f"cannot read {where}: {exc.strerror or exc}") from None
    except (ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise ConfigError(f"cannot read {where}: not an .npz file ({exc})") from None
    for name, (kind, ndim) in arrays.items():
        array = found[name]
        if array.dtype.kind != kind or array.ndim != ndim:
            raise ConfigError(
                f"{where}: array {name!r} must be {ndim}-dimensional of kind {kind!r}, got "
                f"{array.ndim}-dimensional {array.dtype}"
            )
        if kind == "f" and not np.isfinite(array).all():
            raise ConfigError(f"{where}: array {name!r} holds NaN or infinite values")
    return found


def read_json_npz(path: str | os.PathLike[str], what: str) -> Any:
    """Read a JSON document stored as ``.npz`` (:func:`burstloc._atomic.write_json_npz`): the
    text checked as :func:`read_json` checks a file, each ``{"$npz": NAME}`` replaced by its
    array (finite floats; a missing or malformed array named).

    Raises:
        ConfigError: the file cannot be read, the document is not strict JSON, or an array is
            missing or malformed; the message names ``what`` and the file.
    """
    import zipfile

    where = f"{what} {os.fspath(path)}"
    try:
        with np.load(path, allow_pickle=False) as data:
            names = list(data.files)
            if NPZ_DOCUMENT not in names:
                raise ConfigError(f"{where}: no array {NPZ_DOCUMENT!r}")
            utf8 = data[NPZ_DOCUMENT]
            if utf8.dtype != np.uint8 or utf8.ndim != 1:
                raise ConfigError(f"{where}: array {NPZ_DOCUMENT!r} must be UTF-8 bytes")
            try:
                text = utf8.tobytes().decode("utf-8")
            except UnicodeDecodeError as exc:
                raise ConfigError(
                    f"cannot read {where}: not UTF-8 text (byte {exc.start})"
                ) from None
            document = _loads(text, where)
            arrays = read_npz(
                path, what, {name: ("f", data[name].ndim) for name in names if name != "document"}
            )
    except OSError as exc:
        raise ConfigError(f"cannot read {where}: {exc.strerror or exc}") from None
    except (ValueError, EOFError, zipfile.BadZipFile) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(f"cannot read {where}: not an .npz file ({exc})") from None

    def unpack(value: Any, field: str) -> Any:
        if isinstance(value, Mapping):
            if set(value) == {NPZ_REFERENCE}:
                name = value[NPZ_REFERENCE]
                if name not in arrays:
                    raise ConfigError(f"{where}: field {field} refers to no array ({name!r})")
                return arrays[name]
            return {k: unpack(v, f"{field}.{k}" if field else str(k)) for k, v in value.items()}
        if isinstance(value, list):
            return [unpack(v, f"{field}[{i}]") for i, v in enumerate(value)]
        return value

    return unpack(document, "")


def _loads(text: str, where: str) -> Any:
    """Strict JSON text: no NaN or infinity (the field named)."""
    try:
        document = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ConfigError(f"cannot read {where}: not JSON: {exc}") from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer of more than 4300 digits
        raise ConfigError(f"cannot read {where}: {exc}") from None
    field, value = find_non_finite(document)
    if field:
        raise ConfigError(f"{where}: field {field} is {value} (numbers must be finite)")
    return document


def find_non_finite(document: Any, where: str = "") -> tuple[str, str]:
    """The path (``a.b[2]``) and JSON spelling (``NaN``, ``Infinity``, ``-Infinity``) of the
    first non-finite number in a JSON-like document; ``("", "")`` when there is none."""
    if isinstance(document, float) and not math.isfinite(document):
        spelling = "NaN" if math.isnan(document) else ("Infinity" if document > 0 else "-Infinity")
        return where or "(the document)", spelling
    children: Any = ()
    if isinstance(document, Mapping):
        children = ((f"{where}.{k}" if where else str(k), v) for k, v in document.items())
    elif isinstance(document, (list, tuple)):
        children = ((f"{where}[{i}]", v) for i, v in enumerate(document))
    for name, value in children:
        found = find_non_finite(value, name)
        if found[0]:
            return found
    return "", ""


def _kind(value: Any) -> str:
    names = {dict: "an object", list: "a list", str: "a string", bool: "a boolean"}
    if value is None:
        return "null"
    for cls, name in names.items():
        if isinstance(value, cls):
            return name
    return repr(value)


class FieldError(ConfigError):
    """A :class:`~burstloc.exceptions.ConfigError` about one field: ``field`` (its path inside
    the object checked) and ``detail`` (what is wrong), so a reader can prefix the file and the
    path of the object."""

    def __init__(self, field: str, detail: str) -> None:
        super().__init__(f"{field} {detail}")
        self.field = field
        self.detail = detail


def check_number(
    value: Any,
    field: str,
    *,
    low: float = -math.inf,
    high: float = math.inf,
    low_open: bool = False,
) -> float:
    """``value`` as a finite float within ``[low, high]`` (``(low, high]`` with ``low_open``).

    Raises:
        FieldError: not a number, not finite, or out of range (naming ``field``).
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise FieldError(field, f"must be a number, got {_kind(value)}")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    below = number <= low if low_open else number < low
    if not math.isfinite(number) or below or number > high:
        opening = "(" if low_open else "["
        raise FieldError(
            field, f"must be a finite number in {opening}{low:g}, {high:g}], got {value!r}"
        )
    return number


def check_count(value: Any, field: str, *, low: int = 1, high: int) -> int:
    """``value`` as an integer within ``[low, high]`` (an integral float is accepted).

    Raises:
        FieldError: not an integer or out of range (naming ``field``).
    """
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise FieldError(field, f"must be an integer, got {_kind(value)}")
    value = int(value)
    if not low <= value <= high:
        raise FieldError(field, f"must be an integer in [{low}, {high}], got {value}")
    return value


LISTED = 5
"""Most names an error message lists (:func:`some_names`); the rest are counted."""


def some_names(names: Sequence[str], limit: int = LISTED) -> str:
    """The first ``limit`` of ``names`` as a list, and how many more there are:
    ``['n10', 'n11'] and 747 more``; every name when there are no more than ``limit``."""
    shown = repr(list(names[:limit]))
    return shown if len(names) <= limit else f"{shown} and {len(names) - limit} more"


def check_names(
    values: Any, field: str, *, high: int, low: int = 1, max_length: int = 256
) -> tuple[str, ...]:
    """``values`` as a tuple of ``low`` to ``high`` distinct non-empty strings.

    Raises:
        FieldError: not a list of strings, a name listed more than once, too few or too many
            (naming ``field`` and the name).
    """
    if isinstance(values, (str, bytes)) or not isinstance(values, Sequence):
        raise FieldError(field, f"must be a list of names, got {_kind(values)}")
    if not low <= len(values) <= high:
        raise FieldError(field, f"must hold {low} to {high} names, got {len(values)}")
    seen: set[str] = set()
    for value in values:
        if not isinstance(value, str) or not value or len(value) > max_length:
            raise FieldError(
                field, f"must hold names of 1 to {max_length} characters, got {_kind(value)}"
            )
        if value in seen:
            raise FieldError(field, f"lists {value!r} more than once")
        seen.add(value)
    return tuple(values)


def check_string(value: Any, field: str, *, max_length: int = 4096) -> str:
    """``value`` as a string of at most ``max_length`` characters.

    Raises:
        FieldError: not such a string (naming ``field``).
    """
    if not isinstance(value, str) or len(value) > max_length:
        raise FieldError(
            field, f"must be a string of at most {max_length} characters, got {_kind(value)}"
        )
    return value


def attributes(obj: Any, *names: str) -> dict[str, Any]:
    """``{name: obj.name}`` for each of ``names``: the fields a document stores under the
    attributes' own names (the inverse of :meth:`Fields.build`)."""
    return {name: getattr(obj, name) for name in names}


class Fields:
    """One JSON object of a file, read field by field; errors name the file and the field.

    ``source`` names the file; ``path`` is the object's place in the document (``""`` for the
    document itself, else e.g. ``intervals[0]``).

    Raises:
        ConfigError: ``data`` is not a JSON object.
    """

    def __init__(self, data: Any, source: str, path: str = "") -> None:
        self.source = source
        self.path = path
        if not isinstance(data, Mapping):
            where = f"field {path}" if path else "the document"
            raise ConfigError(f"{source}: {where} must be a JSON object, got {_kind(data)}")
        self.data: Mapping[str, Any] = data

    def name(self, key: str | int) -> str:
        """The path of ``key`` inside this object (``a.b``, ``a[0]``)."""
        if isinstance(key, int):
            return f"{self.path}[{key}]"
        return f"{self.path}.{key}" if self.path else key

    @contextlib.contextmanager
    def checking(self) -> Iterator[None]:
        """Name the file and this object's path in a ConfigError raised inside (a
        :class:`FieldError`'s field is read as relative to this object)."""
        try:
            yield
        except FieldError as exc:
            raise ConfigError(f"{self.source}: {self.name(exc.field)} {exc.detail}") from None
        except ConfigError as exc:
            if str(exc).startswith(f"{self.source}: "):
                raise
            where = f"{self.path}: " if self.path else ""
            raise ConfigError(f"{self.source}: {where}{exc}") from None

    def build(
        self,
        cls: Callable[..., T],
        keys: Iterable[str] = (),
        renamed: Mapping[str, str] | None = None,
        **values: Any,
    ) -> T:
        """``cls(...)`` of the required fields ``keys`` (each passed as the keyword of its own
        name), ``renamed`` (keyword -> field) and ``values``; an error it raises named as
        :meth:`checking` names it."""
        with self.checking():
            fields = {key: self.get(key) for key in keys}
            fields.update({kw: self.get(key) for kw, key in (renamed or {}).items()})
            return cls(**fields, **values)

    def get(self, key: str) -> Any:
        """The raw value of a required field."""
        if key not in self.data:
            raise ConfigError(f"{self.source}: field {self.name(key)} is missing")
        return self.data[key]

    def obj(self, key: str) -> Fields:
        """A nested object."""
        return Fields(self.get(key), self.source, self.name(key))

    def objects(self, key: str, *, high: int) -> list[Fields]:
        """A list of 1 to ``high`` objects."""
        items = self.get(key)
        if not isinstance(items, list) or not 1 <= len(items) <= high:
            got = len(items) if isinstance(items, list) else _kind(items)
            raise ConfigError(
                f"{self.source}: field {self.name(key)} must be a list of 1 to {high} objects, "
                f"got {got}"
            )
        return [
            Fields(item, self.source, self.name(key) + f"[{i}]") for i, item in enumerate(items)
        ]

    def optional_object(self, key: str) -> dict[str, Any]:
        """An optional nested object as a dictionary (``{}`` when absent)."""
        return dict(self.obj(key).data) if key in self.data else {}
