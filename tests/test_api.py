"""The façade: every public name resolves to its layer's object, lazily, and is documented."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

import burstloc

API_PAGE = Path(__file__).resolve().parents[1] / "docs" / "api.md"


@pytest.mark.parametrize("name", burstloc.__all__)
def test_every_public_name_resolves(name: str) -> None:
    value = getattr(burstloc, name)
    assert value is not None
    module = getattr(value, "__module__", None)
    if module is not None and name != "__version__":
        # the object is the layer's own, not a copy
        assert getattr(sys.modules[module], name) is value


def test_unknown_names_raise_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'Nope'"):
        _ = burstloc.Nope  # type: ignore[attr-defined]


def _loaded_after(statement: str, prefixes: tuple[str, ...]) -> list[str]:
    """The modules of ``wntr``, ``tsnet`` or under ``prefixes`` that a fresh interpreter has
    loaded after running ``statement``."""
    code = (
        f"import sys; {statement}; "
        "print('\\n'.join(m for m in sys.modules if m.split('.')[0] in ('wntr', 'tsnet') "
        f"or m.startswith({prefixes!r})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return sorted(out.stdout.split())


def test_importing_burstloc_loads_no_layer_and_no_simulator() -> None:
    layers = tuple(f"burstloc.{p}" for p in ("sim", "live", "localize", "experiments", "cli"))
    assert _loaded_after("import burstloc", layers) == []
    assert "burstloc.sim.transient.tsnet" in _loaded_after(
        "import burstloc.sim.transient.tsnet", layers
    )


def test_the_live_names_do_not_load_the_simulator() -> None:
    live = "import burstloc; burstloc.BurstMonitor; burstloc.Calibration; burstloc.Decision"
    assert _loaded_after(live, ("burstloc.sim", "burstloc.experiments")) == []


def test_the_api_page_lists_every_public_name() -> None:
    text = API_PAGE.read_text()
    listed = set(re.findall(r"^\| `(\w+)", text, flags=re.MULTILINE))
    assert listed == set(burstloc.__all__) - {"__version__"}
