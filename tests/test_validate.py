"""burstloc._validate: strict JSON reading and field checks whose errors name file and field."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from burstloc._validate import (
    FieldError,
    Fields,
    check_count,
    check_names,
    check_number,
    find_non_finite,
    read_json,
)
from burstloc.exceptions import ConfigError


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\xff\xfe{}", r"cannot read thing .*x\.json: not UTF-8 text \(byte 0\)"),
        (b"", r"cannot read thing .*x\.json: not JSON"),
        (b'{"a": [1, 2', r"cannot read thing .*x\.json: not JSON"),
        (b'{"a": {"b": [1, NaN]}}', r"thing .*x\.json: field a\.b\[1\] is NaN"),
        (b'{"a": -Infinity}', r"thing .*x\.json: field a is -Infinity"),
        (b'{"a": 1e999}', r"thing .*x\.json: field a is Infinity"),
        (b'{"a": ' + b"9" * 5000 + b"}", r"cannot read thing .*x\.json: .*digits"),
    ],
)
def test_read_json_refuses_what_is_not_strict_json(
    tmp_path: Path, content: bytes, message: str
) -> None:
    path = tmp_path / "x.json"
    path.write_bytes(content)
    with pytest.raises(ConfigError, match=message):
        read_json(path, "thing")


def test_read_json_reads_strict_json_and_names_a_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "x.json"
    path.write_text('{"a": [1, 2.5, "z"], "b": null}')
    assert read_json(path, "thing") == {"a": [1, 2.5, "z"], "b": None}
    with pytest.raises(ConfigError, match=r"cannot read thing .*missing\.json: No such file"):
        read_json(tmp_path / "missing.json", "thing")
    with pytest.raises(ConfigError, match=r"cannot read thing .*: Is a directory"):
        read_json(tmp_path, "thing")


def test_find_non_finite_names_the_first_path() -> None:
    assert find_non_finite({"a": [1.0, {"b": 2.0}]}) == ("", "")
    assert find_non_finite({"a": [1.0, {"b": math.inf}]}) == ("a[1].b", "Infinity")
    assert find_non_finite([math.nan]) == ("[0]", "NaN")
    assert find_non_finite(-math.inf) == ("(the document)", "-Infinity")


def test_checks_name_the_field_and_the_value() -> None:
    assert check_number(np.float32(2.5), "x", low=0, low_open=True) == 2.5
    assert check_count(np.int64(7), "n", high=10) == 7 and check_count(3.0, "n", high=10) == 3
    assert check_names(["a", "b"], "m", high=5) == ("a", "b")
    cases = [
        (lambda: check_number("1", "x"), r"x must be a number, got a string"),
        (lambda: check_number(True, "x"), r"x must be a number, got a boolean"),
        (lambda: check_number(math.nan, "x"), r"x must be a finite number in \[-inf, inf\]"),
        (lambda: check_number(0, "x", low=0, low_open=True), r"x must be .* in \(0, inf\], got 0"),
        (lambda: check_number(10**400, "x", high=5), r"x must be a finite number in \[-inf, 5\]"),
        (lambda: check_count(2**64, "n", high=10), r"n must be an integer in \[1, 10\], got 1844"),
        (lambda: check_count(1.5, "n", high=10), r"n must be an integer, got 1\.5"),
        (lambda: check_names("ab", "m", high=5), r"m must be a list of names, got a string"),
        (lambda: check_names(["a", "a"], "m", high=5), r"m lists 'a' more than once"),
        (lambda: check_names(["a", 3], "m", high=5), r"m must hold names of 1 to 256"),
        (lambda: check_names([], "m", high=5), r"m must hold 1 to 5 names, got 0"),
    ]
    for call, message in cases:
        with pytest.raises(FieldError, match=message):
            call()


def test_fields_name_the_source_and_the_path() -> None:
    doc = Fields({"a": {"b": [{"c": 1}, 2]}, "n": "x"}, "config f.json")
    assert doc.obj("a").name("b") == "a.b"
    with pytest.raises(
        ConfigError, match=r"^config f\.json: field a\.b\[1\] must be a JSON object"
    ):
        doc.obj("a").objects("b", high=5)
    with pytest.raises(ConfigError, match=r"^config f\.json: field a\.z is missing"):
        doc.obj("a").get("z")
    with pytest.raises(ConfigError, match=r"^config f\.json: field a\.b must be a list of 1 to 1"):
        doc.obj("a").objects("b", high=1)
    with pytest.raises(ConfigError, match=r"^config f\.json: the document must be a JSON object"):
        Fields([1], "config f.json")
    (item, _) = Fields({"b": [{"c": 1}, {"c": 2}]}, "f").objects("b", high=5)
    field_error = r"^f: b\[0\]\.c must be an integer in \[5, 9\], got 1"
    with pytest.raises(ConfigError, match=field_error), item.checking():
        check_count(item.get("c"), "c", low=5, high=9)
    with pytest.raises(ConfigError, match=r"^f: b\[0\]: other problem"), item.checking():
        raise ConfigError("other problem")


def test_json_npz_round_trip_and_checks(tmp_path: Path) -> None:
    from burstloc._atomic import write_json_npz
    from burstloc._validate import read_json_npz
    from burstloc.exceptions import OutputError

    rows = [[0.1 * i + j for j in range(3)] for i in range(4)]
    document = {"name": "x", "rows": rows, "counts": [1, 2, 3, 4], "flags": [True] * 20}
    path = write_json_npz(tmp_path / "d.npz", document, min_size=12)
    back = read_json_npz(path, "document")
    assert isinstance(back["rows"], np.ndarray) and back["rows"].tolist() == rows
    assert back["counts"] == [1, 2, 3, 4] and back["flags"] == [True] * 20  # stay JSON
    assert back["name"] == "x"
    with pytest.raises(OutputError, match=r"field rows\[0\]\[1\] is NaN"):
        write_json_npz(tmp_path / "n.npz", {"rows": [[1.0, math.nan]]})
    # a reference to no array, a NaN array, a foreign file: named
    text = np.frombuffer(b'{"rows": {"$npz": "a9"}}', dtype=np.uint8)
    np.savez(tmp_path / "ref.npz", document=text)
    with pytest.raises(ConfigError, match="field rows refers to no array"):
        read_json_npz(tmp_path / "ref.npz", "document")
    text = np.frombuffer(b'{"rows": {"$npz": "a0"}}', dtype=np.uint8)
    np.savez(tmp_path / "nan.npz", document=text, a0=np.array([np.nan]))
    with pytest.raises(ConfigError, match="'a0' holds NaN"):
        read_json_npz(tmp_path / "nan.npz", "document")
    np.savez(tmp_path / "none.npz", rows=np.ones(3))
    with pytest.raises(ConfigError, match="no array 'document'"):
        read_json_npz(tmp_path / "none.npz", "document")
    (tmp_path / "text.npz").write_text("{}")
    with pytest.raises(ConfigError, match=r"not an \.npz file"):
        read_json_npz(tmp_path / "text.npz", "document")
