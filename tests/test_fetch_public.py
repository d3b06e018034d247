"""networks/fetch_public.py: the public networks come from the pinned epyt wheel, every file is
checked against its pinned SHA-256, a changed file is refused by name.

These run on the real wheel that ``make networks`` downloads and keeps in ``networks/public/``.
"""

from __future__ import annotations

import importlib.util
import json
import shutil
import sys
import zipfile
from pathlib import Path
from types import ModuleType

import pytest

from conftest import REPO


def _load() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "fetch_public", REPO / "networks" / "fetch_public.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


fetch_public = _load()


@pytest.fixture(scope="module")
def wheel() -> Path:
    """The pinned epyt wheel kept by ``make networks``."""
    path = fetch_public.PUBLIC / fetch_public.WHEEL
    assert path.is_file(), f"{path} is missing: run `make networks`"
    return path


def test_extract_from_the_real_wheel_writes_the_pinned_files(wheel: Path, tmp_path: Path) -> None:
    written = fetch_public.extract(wheel, tmp_path)
    assert [p.name for p in written] == ["Net1.inp", "Net2.inp", "Net3.inp", "Anytown.inp"]
    for net, path in zip(fetch_public.NETWORKS, written, strict=True):
        assert fetch_public.sha256_of(path) == net.sha256
        assert "[JUNCTIONS]" in path.read_text(encoding="utf-8", errors="replace")
    fetch_public.check(tmp_path)  # accepts what it extracted
    manifest = json.loads((tmp_path / "MANIFEST.json").read_text(encoding="utf-8"))
    assert manifest["source"]["url"].endswith(fetch_public.WHEEL)
    assert {n["name"] for n in manifest["networks"]} == {n.name for n in fetch_public.NETWORKS}
    assert all(n["licence"] == "EUPL-1.2" for n in manifest["networks"])
    licence = (tmp_path / "LICENSE-epyt.md").read_text(encoding="utf-8")
    assert licence.startswith("EUROPEAN UNION PUBLIC LICENCE v. 1.2")


def test_the_fetched_networks_are_the_pinned_ones() -> None:
    fetch_public.check()  # networks/public as `make networks` left it


def test_a_changed_network_is_refused_by_name(wheel: Path, tmp_path: Path) -> None:
    fetch_public.extract(wheel, tmp_path)
    net2 = tmp_path / "Net2.inp"
    net2.write_bytes(net2.read_bytes().replace(b"[PIPES]", b"[PIPES]\n 999 1 2 10 100 100 0 Open"))
    with pytest.raises(fetch_public.FetchError, match=r"Net2\.inp has SHA-256 [0-9a-f]{64}"):
        fetch_public.check(tmp_path)
    assert fetch_public.main(["--check", "--out", str(tmp_path)]) == 1
    # fetching again restores it from the kept wheel, with no download
    shutil.copyfile(wheel, tmp_path / fetch_public.WHEEL)
    assert "extracted" in fetch_public.fetch(tmp_path)
    fetch_public.check(tmp_path)
    assert "as pinned" in fetch_public.fetch(tmp_path)


def test_a_changed_wheel_is_refused(wheel: Path, tmp_path: Path) -> None:
    changed = tmp_path / fetch_public.WHEEL
    with zipfile.ZipFile(wheel) as source, zipfile.ZipFile(changed, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename.endswith("/Net1.inp"):
                data = data.replace(b"[JUNCTIONS]", b"[JUNCTIONS]\n 99 0 0")
            target.writestr(item, data)
    out = tmp_path / "out"
    with pytest.raises(fetch_public.FetchError, match=r"epyt-.*\.whl has SHA-256"):
        fetch_public.extract(changed, out)
    assert not (out / "Net1.inp").exists()


def test_no_connection_says_what_to_do(tmp_path: Path) -> None:
    # port 9 (discard) on the loopback: refused at once, nothing is left behind
    with pytest.raises(fetch_public.FetchError, match="make networks"):
        fetch_public.download(tmp_path, url="http://127.0.0.1:9/epyt.whl", timeout=5)
    assert list(tmp_path.iterdir()) == []


def test_the_library_is_every_network_of_the_wheel_with_its_terms(
    wheel: Path, tmp_path: Path
) -> None:
    written = fetch_public.extract_library(wheel, tmp_path)
    with zipfile.ZipFile(wheel) as archive:
        members = [m for m in archive.namelist() if m.lower().endswith(".inp")]
    assert len(written) == len([m for m in members if m.startswith("epyt/networks/")]) > 40
    document = json.loads((tmp_path / "LIBRARY.json").read_text(encoding="utf-8"))
    records = {r["path"]: r for r in document["networks"]}
    assert set(records) == {p.relative_to(tmp_path).as_posix() for p in written}
    for path in written:
        record = records[path.relative_to(tmp_path).as_posix()]
        assert fetch_public.sha256_of(path) == record["sha256"]
    assert "non-commercial" in records["asce-tf-wdst/ky1.inp"]["terms"]
    assert "non-commercial" not in records["L-TOWN.inp"]["terms"]
    assert document["wheel_sha256"] == fetch_public.WHEEL_SHA256
    assert (tmp_path / "LICENSE-epyt.md").is_file()
