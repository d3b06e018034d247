"""The package's layers import only downwards, with no import cycle (every import, lazy ones too).

Layers: the base (``exceptions``, ``constants``, ``network``, ``readings``, ``_atomic``, ...),
``localize`` (base only), ``live`` (base and localize: the live path never reaches the
simulator), ``incidents`` (base and live: the monitor's records kept), ``web`` (base, live and
incidents: the control-room page shows the monitor's own records),
``sim`` (base and localize, whose model it prepares offline), ``experiments`` (all
of those) and ``cli`` (anything; nothing imports it). Inside ``sim``, its rooms import one
another in one order too (:data:`SIM_ROOMS`).
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "python" / "burstloc"
LAYERS = ("localize", "live", "incidents", "web", "sim", "experiments", "cli")
ALLOWED: dict[str, set[str]] = {
    "base": {"base"},
    "localize": {"base", "localize"},
    "live": {"base", "localize", "live"},
    # the incident store keeps the monitor's own records: never the simulator
    "incidents": {"base", "live", "incidents"},
    # the control-room page reads only the monitor's own records: never the simulator
    "web": {"base", "live", "incidents", "web"},
    "sim": {"base", "localize", "sim"},
    "experiments": {"base", "localize", "live", "sim", "experiments"},
    "cli": {"base", "localize", "live", "incidents", "web", "sim", "experiments", "cli"},
}


#: ``sim``'s sub-packages and the rooms each may import (besides the base and ``localize``).
SIM_ROOMS: dict[str, set[str]] = {
    "scenarios": {"scenarios"},
    "transient": {"scenarios", "transient"},
    "events": {"scenarios", "transient", "events"},
    "signatures": {"scenarios", "signatures"},
    "model": {"scenarios", "signatures", "model"},
    "placement": {"scenarios", "signatures", "model", "placement"},
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _layer(module: str) -> str:
    if module == "burstloc.__main__":  # ``python -m burstloc``: the command line
        return "cli"
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYERS else "base"


def _imports(path: Path) -> set[str]:
    """Every ``burstloc`` module ``path`` imports, at module level or inside functions."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] == "burstloc"}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] != "burstloc":
                continue
            for alias in node.names:  # `from burstloc.sim import tsnet` imports a module
                sub = f"{node.module}.{alias.name}"
                found.add(sub if _exists(sub) else node.module)
    return found


def _exists(module: str) -> bool:
    rel = Path(*module.split("."))
    return (PACKAGE.parent / rel).with_suffix(".py").is_file() or (
        PACKAGE.parent / rel / "__init__.py"
    ).is_file()


def _graph() -> nx.DiGraph:
    graph = nx.DiGraph()
    for path in sorted(PACKAGE.rglob("*.py")):
        module = _module_name(path)
        graph.add_node(module)
        for target in _imports(path):
            if target != module:
                graph.add_edge(module, target)
    return graph


def test_the_graph_sees_the_package() -> None:
    graph = _graph()
    assert {"burstloc.live.monitor", "burstloc.sim.transient.tsnet", "burstloc.cli"} <= set(graph)
    assert graph.has_edge("burstloc.live.monitor", "burstloc.localize.config")


@pytest.mark.parametrize("layer", sorted(ALLOWED))
def test_layers_import_only_downwards(layer: str) -> None:
    graph = _graph()
    wrong = sorted(
        f"{source} imports {target}"
        for source, target in graph.edges
        if _layer(source) == layer
        and _layer(target) not in ALLOWED[layer]
        and source != "burstloc"  # the façade re-exports from every layer, lazily
    )
    assert not wrong, wrong


def _room(module: str) -> str | None:
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[1] == "sim" else None


def test_sim_is_rooms_only() -> None:
    """Every module of ``sim`` lives in a room; no room is unknown to :data:`SIM_ROOMS`."""
    sim = PACKAGE / "sim"
    loose = sorted(p.name for p in sim.glob("*.py") if p.name != "__init__.py")
    rooms = {p.name for p in sim.iterdir() if (p / "__init__.py").is_file()}
    assert not loose, loose
    assert rooms == set(SIM_ROOMS)


def test_sim_rooms_import_in_order() -> None:
    graph = _graph()
    wrong = sorted(
        f"{source} imports {target}"
        for source, target in graph.edges
        if (room := _room(source)) is not None
        and (other := _room(target)) is not None
        and other not in SIM_ROOMS[room]
    )
    assert graph.has_edge("burstloc.sim.placement.methods", "burstloc.sim.model.prepare")
    assert not wrong, wrong


def test_nothing_imports_the_cli() -> None:
    graph = _graph()
    users = sorted(s for s, t in graph.edges if _layer(t) == "cli" and _layer(s) != "cli")
    assert not users, users


def test_no_import_cycle() -> None:
    graph = _graph()
    graph.remove_node("burstloc")  # the façade: imports from the layers, imported by none
    cycles = list(nx.simple_cycles(graph))
    assert not cycles, cycles


def test_the_live_path_and_the_page_never_import_a_hydraulic_model() -> None:
    roots = [PACKAGE / "live", PACKAGE / "web", PACKAGE / "layout.py"]
    files = [p for r in roots for p in ([r] if r.is_file() else sorted(r.rglob("*.py")))]
    wrong = []
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            wrong += [f"{path.name}: {n}" for n in names if n.split(".")[0] in ("wntr", "tsnet")]
    assert len(files) > 10
    assert not wrong, wrong
