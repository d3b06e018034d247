"""burstloc.sim.transient._tsnet_compat: TSNet on numpy 2 and WNTR >= 1.4, heads as on the pinned
stack.

Two bursts (3 s, real TSNet runs): pipe 7 of the shipped paper15 network, and the tiny test
network with a dead-end branch that carries no flow (the pipe TSNet gives zero roughness).
``tsnet_reference.npz`` holds their heads from the pinned stack (numpy 1.26, WNTR 1.3.2,
TSNet 0.3.1, unpatched); rewrite it there with
``PYTHONPATH=tests .venv/bin/python tests/sim/test_tsnet_compat.py``.

* on the pinned stack the patched TSNet gives, bit for bit, the heads of unpatched TSNet run
  here, and the stored reference within :data:`MACHINE_ATOL` (the reference was computed on
  another CPU, whose numpy/EPANET kernels round differently: measured 1.1e-5 m);
* on numpy 2 + WNTR 1.5 (which solve the same steady state but round the transient
  differently; measured: at most 6e-5 m) it reproduces the reference within
  :data:`NUMPY2_ATOL`;
* each patch, taken away alone: on the pinned stack the heads stay bit-identical to unpatched
  TSNet (the patch changes no number); on numpy 2 / WNTR >= 1.4 TSNet fails as it does
  unpatched.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from burstloc.exceptions import SimulationError
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient import _tsnet_compat
from burstloc.sim.transient.tsnet import simulate_burst
from conftest import TINY_INP

REFERENCE = Path(__file__).with_name("tsnet_reference.npz")
#: Largest head difference (m) allowed between numpy 2 + WNTR 1.5 and the pinned stack.
NUMPY2_ATOL = 1e-3
#: Largest head difference (m) allowed between the pinned stack here and the stored reference.
MACHINE_ATOL = 1e-4
#: TSNet's own solver: this file checks TSNet (tests/sim/test_moc.py checks the vectorized one).
SHORT = {"burst_start": 0.5, "duration": 3.0, "solver": "tsnet"}


def with_dead_end(elevation: float) -> str:
    """The tiny network of conftest plus a dead-end branch J4 -> J5 (J5 at ``elevation``, m,
    without demand: no flow in F)."""
    return (
        TINY_INP.format(head=60.0)
        .replace("\n\n[RESERVOIRS]", f"\n J5   {elevation:g}      0\n\n[RESERVOIRS]")
        .replace(
            "\n\n[OPTIONS]",
            "\n F    J4     J5     120     100       100        0   Open\n\n[OPTIONS]",
        )
        .replace("\n\n[END]", "\n J5   800   -100\n\n[END]")
    )


BRANCH_INP = with_dead_end(0.0)

#: The patched functions: the module attribute TSNet calls, by the key of its original.
PATCHES = {
    "cal_N": ("tsnet.network.discretize", "cal_N"),
    "adjust_wavev": ("tsnet.network.discretize", "adjust_wavev"),
    "add_leakage": ("tsnet.simulation.single", "add_leakage"),
    "cal_roughness_coef": ("tsnet.simulation.initialize", "cal_roughness_coef"),
}
#: The patches that let TSNet start below atmospheric pressure (a junction without demand).
NEGATIVE_PRESSURE_PATCHES = {
    "cal_demand_coef": ("tsnet.simulation.initialize", "cal_demand_coef"),
    "dead_end": ("tsnet.simulation.single", "dead_end"),
}
#: J5 at 70 m, above the reservoir's 60 m grade: a dead end without demand at about -10 m of
#: pressure (EPANET's steady state), as Net3's junction 10.
ABOVE_GRADE_INP = with_dead_end(70.0)

#: The patches that make TSNet's valve and pump operations run (tests/sim/test_events.py runs
#: them): the attribute of the module or class TSNet calls, by the key of its original.
OPERATION_PATCHES = {
    "pump_operation_points": ("tsnet.simulation.initialize", "pump_operation_points"),
    "valve_opening": ("tsnet.network.model", "TransientModel.valve_opening"),
    "pump_start_up": ("tsnet.network.model", "TransientModel.pump_start_up"),
}


def pinned_stack() -> bool:
    """Whether this is the stack the reference was computed with."""
    return metadata.version("wntr") == "1.3.2" and np.__version__.startswith("1.26")


def scenarios(directory: Path) -> dict[str, BurstScenario]:
    """The two reference bursts (the branch network is written into ``directory``)."""
    branch = directory / "branch.inp"
    branch.write_text(BRANCH_INP, encoding="utf-8")
    paper15 = Path(__file__).resolve().parents[2] / "networks" / "paper15.inp"
    return {
        "paper15_pipe7": BurstScenario(paper15, "7", **SHORT),
        "branch_pipe_E": BurstScenario(branch, "E", **SHORT),
    }


def heads(scenario: BurstScenario) -> np.ndarray:
    """Simulated pressure heads (no cache)."""
    return simulate_burst(scenario, cache=False).heads


def unpatched_heads(scenario: BurstScenario) -> np.ndarray:
    """Heads from TSNet without any of the patches (runs on the pinned stack only)."""
    _tsnet_compat.load()
    patched = {name: getattr(sys.modules[m], a) for name, (m, a) in PATCHES.items()}
    for name, (module, attribute) in PATCHES.items():
        setattr(sys.modules[module], attribute, _tsnet_compat._ORIGINALS[name])
    try:
        return heads(scenario)
    finally:
        for name, (module, attribute) in PATCHES.items():
            setattr(sys.modules[module], attribute, patched[name])


@pytest.fixture(scope="module")
def bursts(tmp_path_factory: pytest.TempPathFactory) -> dict[str, BurstScenario]:
    return scenarios(tmp_path_factory.mktemp("compat"))


@pytest.fixture(scope="module")
def reference() -> dict[str, np.ndarray]:
    with np.load(REFERENCE) as stored:
        return {name: stored[name] for name in stored.files}


@pytest.fixture(scope="module")
def unpatched(bursts: dict[str, BurstScenario]) -> dict[str, np.ndarray]:
    """On the pinned stack, unpatched TSNet's heads computed here; elsewhere it cannot run."""
    return {name: unpatched_heads(s) for name, s in bursts.items()} if pinned_stack() else {}


@pytest.fixture
def without(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    """TSNet patched except for the patch named by the test's parameter."""
    _tsnet_compat.load()
    name = request.param
    module, attribute = PATCHES[name]
    monkeypatch.setattr(sys.modules[module], attribute, _tsnet_compat._ORIGINALS[name])
    yield name


def test_the_patches_are_the_functions_tsnet_calls() -> None:
    _tsnet_compat.load()
    assert _tsnet_compat.applied()
    every = {**PATCHES, **OPERATION_PATCHES, **NEGATIVE_PRESSURE_PATCHES}
    assert set(_tsnet_compat._ORIGINALS) == set(every)
    for name, (module, attribute) in every.items():
        patched: Any = sys.modules[module]
        for part in attribute.split("."):
            patched = getattr(patched, part)
        assert patched is not _tsnet_compat._ORIGINALS[name]
        assert patched.__module__ == "burstloc.sim.transient._tsnet_compat"


@pytest.mark.parametrize("name", ["paper15_pipe7", "branch_pipe_E"])
def test_heads_match_the_pinned_stack(
    name: str,
    bursts: dict[str, BurstScenario],
    reference: dict[str, np.ndarray],
    unpatched: dict[str, np.ndarray],
) -> None:
    got = heads(bursts[name])
    assert got.shape == reference[name].shape
    if pinned_stack():
        np.testing.assert_array_equal(got, unpatched[name])
        np.testing.assert_allclose(got, reference[name], rtol=0, atol=MACHINE_ATOL)
    else:
        np.testing.assert_allclose(got, reference[name], rtol=0, atol=NUMPY2_ATOL)
        assert not np.array_equal(got[1:], got[:-1])  # a transient, not a constant


def test_the_branch_has_a_pipe_without_flow(
    bursts: dict[str, BurstScenario], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The roughness patch's case happens: TSNet sees pipe F with no steady flow."""
    _tsnet_compat.load()
    module = sys.modules["tsnet.simulation.initialize"]
    patched = module.cal_roughness_coef
    speeds: dict[str, float] = {}

    def spy(pipe: Any, velocity: float, head_loss: float) -> Any:
        speeds[str(pipe.name)] = float(abs(velocity))
        return patched(pipe, velocity, head_loss)

    monkeypatch.setattr(module, "cal_roughness_coef", spy)
    heads(bursts["branch_pipe_E"])
    assert speeds["F"] < 1e-5 and speeds["A"] > 1e-3


@pytest.mark.parametrize("without", list(PATCHES), indirect=True)
def test_each_patch_is_needed_and_changes_no_number(
    without: str, bursts: dict[str, BurstScenario], unpatched: dict[str, np.ndarray]
) -> None:
    name = "branch_pipe_E"
    if pinned_stack():
        np.testing.assert_array_equal(heads(bursts[name]), unpatched[name])
    else:
        with pytest.raises(SimulationError):
            heads(bursts[name])


@pytest.fixture(scope="module")
def above_grade(tmp_path_factory: pytest.TempPathFactory) -> BurstScenario:
    path = tmp_path_factory.mktemp("above") / "above_grade.inp"
    path.write_text(ABOVE_GRADE_INP, encoding="utf-8")
    return BurstScenario(path, "E", **SHORT)


def test_a_dead_end_below_atmospheric_pressure_starts_steady(above_grade: BurstScenario) -> None:
    result = simulate_burst(above_grade, cache=False)
    j5 = result.heads[:, result.junctions.index("J5")]
    assert np.isfinite(result.heads).all()
    assert -12.0 < j5[0] < -8.0  # EPANET's steady state: below atmospheric pressure
    before = result.time < above_grade.burst_start
    assert np.ptp(j5[before]) < 1e-3  # held, not pulled up to the elevation
    assert j5.max() < 0  # it stays below: nothing is drawn from a dead end without demand
    assert not np.array_equal(result.heads[-1], result.heads[0])  # the burst is simulated


@pytest.mark.parametrize(
    ("patch", "error"), [("cal_demand_coef", "non-finite"), ("dead_end", "before the")]
)
def test_each_negative_pressure_patch_is_needed(
    patch: str, error: str, above_grade: BurstScenario, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without the demand patch TSNet's heads turn NaN; without the dead-end patch the dead end
    jumps 10 m to its elevation at the first step, and the steady-start check refuses it."""
    _tsnet_compat.load()
    module, attribute = NEGATIVE_PRESSURE_PATCHES[patch]
    monkeypatch.setattr(sys.modules[module], attribute, _tsnet_compat._ORIGINALS[patch])
    with pytest.raises(SimulationError, match=error):
        simulate_burst(above_grade, cache=False)


def write_reference(directory: Path) -> None:
    """Compute the reference heads with unpatched TSNet (on the pinned stack only)."""
    if not pinned_stack():
        raise SystemExit("the reference comes from the pinned stack (numpy 1.26, WNTR 1.3.2)")
    arrays = {name: unpatched_heads(s) for name, s in scenarios(directory).items()}
    np.savez_compressed(REFERENCE, **arrays)  # type: ignore[arg-type]
    print(f"wrote {REFERENCE}: " + ", ".join(f"{k} {v.shape}" for k, v in arrays.items()))


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        write_reference(Path(tmp))
