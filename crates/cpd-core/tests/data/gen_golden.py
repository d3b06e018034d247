"""Generate the golden outputs that `tests/golden_tsnet.rs` compares `cpd-core` against.

CUSUM: TSNet 0.3.1's own `tsnet.postprocessing.detect_cusum` (the paper's Algorithm 1).
Shewhart: the paper's Algorithm 2 written with NumPy (`np.mean`, `np.std`), with the
amplitude threshold separate from the multiplier `sigma` as in the crate.

Run from the repository root (pinned env: numpy 1.26.4, tsnet 0.3.1):

    .venv/bin/python crates/cpd-core/tests/data/gen_golden.py

It rewrites `cusum_golden.json` and `shewhart_golden.json` next to this file. Every case is
tagged with the branch of TSNet's `ending` post-processing it exercises; the script fails if a
branch is not covered.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import tsnet
from tsnet.postprocessing.detect_cusum import detect_cusum

HERE = Path(__file__).resolve().parent
BRANCHES = ("no_alarm", "equal", "fewer_starts", "more_starts", "wrap_minus_one", "intercalated")


def tsnet_cusum(x: np.ndarray, threshold: float, drift: float, ending: bool):
    time = np.arange(x.size, dtype=float)
    return detect_cusum(time, x, threshold, drift, show=False, ending=ending)


def branches(x: np.ndarray, threshold: float, drift: float) -> list[str]:
    """Which parts of TSNet's `ending` post-processing this input reaches (for coverage)."""
    tai, _, _ = tsnet_cusum(x, threshold, drift, ending=False)
    if tai.size == 0:
        return ["no_alarm"]
    tai2, _, _ = tsnet_cusum(x[::-1], threshold, drift, ending=False)
    taf = x.size - tai2[::-1] - 1
    # ta is needed for the selections: rerun the online pass to get the alarm indices.
    ta = online_alarms(x, threshold, drift)
    u, ind = np.unique(tai, return_index=True)
    ta = ta[ind]
    tags = []
    if u.size == taf.size:
        tags.append("equal")
    elif u.size < taf.size:
        tags.append("fewer_starts")
        taf = taf[[np.argmax(taf >= i) for i in ta]]
    else:
        tags.append("more_starts")
        ks = [np.argmax(i >= ta[::-1]) for i in taf]
        if any(k == 0 for k in ks):
            tags.append("wrap_minus_one")
        ind = [k - 1 for k in ks]
        u = u[ind]
    if (taf[:-1] - u[1:] > 0).any():
        tags.append("intercalated")
    return tags


def online_alarms(x: np.ndarray, threshold: float, drift: float) -> np.ndarray:
    """Alarm indices `ta` of TSNet's online pass (TSNet does not return them)."""
    gp = gn = gpr = gnr = 0.0
    ta = []
    for i in range(1, x.size):
        s = x[i] - x[i - 1]
        gp, gpr, gn, gnr = gp + s - drift, gpr + s, gn - s - drift, gnr - s
        if gp < 0:
            gp, gpr = 0.0, 0.0
        if gn < 0:
            gn, gnr = 0.0, 0.0
        if gpr > threshold or gnr > threshold:
            ta.append(i)
            gp = gn = gpr = gnr = 0.0
    return np.array(ta, dtype=int)


def signals(rng: np.random.Generator):
    """(name, x, threshold, drift) cases: steps, ramps, noise, transients, random walks."""
    base = np.full(200, 200.0)
    step_down = base.copy()
    step_down[80:] -= 1.5
    yield "step_down", step_down, 0.5, 0.01
    step_up = base.copy()
    step_up[50:] += 0.8
    yield "step_up", step_up, 0.3, 0.0
    two = base.copy()
    two[40:] -= 1.0
    two[120:] += 2.0
    yield "two_steps", two, 0.5, 0.05
    yield "ramp_up", 200.0 + 0.01 * np.arange(300), 0.5, 0.0
    yield "ramp_down_drift", 200.0 - 0.01 * np.arange(300), 0.5, 0.005
    t = np.arange(400) * 0.01
    transient = 200.0 - 2.0 * (t > 1.0) * (1 + 0.5 * np.exp(-(t - 1.0)) * np.cos(20 * (t - 1.0)))
    yield "burst_transient", transient + rng.normal(0, 1e-3, t.size), 0.3, 0.01
    yield "empty", np.array([]), 1.0, 0.0
    yield "single", np.array([5.0]), 1.0, 0.0
    yield "two_jump", np.array([0.0, 3.0]), 1.0, 0.0
    for k in range(40):
        n = int(rng.integers(20, 400))
        kind = k % 4
        if kind == 0:
            x = rng.normal(200.0, 0.5, n)
        elif kind == 1:
            x = 200.0 + np.cumsum(rng.normal(0, 0.3, n))
        elif kind == 2:
            x = np.round(rng.normal(0, 2.0, n))  # integer values: ties and repeated starts
        else:
            x = 100.0 + np.repeat(rng.normal(0, 1.0, n // 10 + 1), 10)[:n] + rng.normal(0, 0.05, n)
        threshold = float(rng.choice([0.2, 0.5, 1.0, 2.0, 3.0]))
        drift = float(rng.choice([0.0, 0.01, 0.1, 0.5]))
        yield f"random_{k}", x, threshold, drift


def hunt(rng: np.random.Generator, wanted: str):
    """Random short integer-valued signals until one reaches the `wanted` branch."""
    for _ in range(200_000):
        n = int(rng.integers(5, 40))
        x = np.round(rng.normal(0, 2.0, n)).astype(float)
        threshold = float(rng.choice([0.5, 1.0, 2.0, 3.0]))
        drift = float(rng.choice([0.0, 0.5, 1.0]))
        if wanted in branches(x, threshold, drift):
            return x, threshold, drift
    raise RuntimeError(f"no case found for branch {wanted}")


def main() -> None:
    rng = np.random.default_rng(20240601)
    cases = list(signals(rng))
    for wanted in BRANCHES:
        for j in range(3):
            x, threshold, drift = hunt(rng, wanted)
            cases.append((f"hunt_{wanted}_{j}", x, threshold, drift))
    cusum = []
    covered: set[str] = set()
    for name, x, threshold, drift in cases:
        tags = branches(x, threshold, drift) if x.size else ["no_alarm"]
        covered.update(tags)
        for ending in (True, False):
            tai, taf, amp = tsnet_cusum(x, threshold, drift, ending)
            cusum.append(
                {
                    "name": name,
                    "branches": tags,
                    "x": x.tolist(),
                    "threshold": threshold,
                    "drift": drift,
                    "ending": ending,
                    "start": [int(v) for v in tai],
                    "end": [int(v) for v in taf],
                    "amplitude": [float(v) for v in amp],
                }
            )
    missing = set(BRANCHES) - covered
    if missing:
        raise RuntimeError(f"branches not covered: {sorted(missing)}")

    shewhart = []
    for k in range(30):
        n = int(rng.integers(2, 300))
        if k % 3 == 0:
            x = 200.0 + rng.normal(0, 1e-3, n)
            x[n // 2 :] -= rng.choice([0.0, 0.002, 0.5])
        elif k % 3 == 1:
            x = np.round(rng.normal(0, 2.0, n))
        else:
            x = rng.normal(0, 1.0, n) * rng.choice([1.0, 1e3], n)
        for sigma, threshold in ((1.0, 1e-3), (2.0, 0.5), (3.0, 0.001), (0.5, 1.0)):
            mean, std = np.mean(x), np.std(x)
            idx = [
                i
                for i in range(x.size)
                if abs(x[i] - mean) > sigma * std and abs(x[i] - mean) > threshold
            ]
            shewhart.append(
                {
                    "x": x.tolist(),
                    "sigma": sigma,
                    "threshold": threshold,
                    "index": idx,
                    "amplitude": [float(v) for v in np.abs(x[idx] - mean)],
                }
            )
    versions = {"numpy": np.__version__, "tsnet": tsnet.__version__}
    (HERE / "cusum_golden.json").write_text(json.dumps({"versions": versions, "cases": cusum}))
    (HERE / "shewhart_golden.json").write_text(
        json.dumps({"versions": versions, "cases": shewhart})
    )
    print(f"{len(cusum)} CUSUM cases, branches {sorted(covered)}; {len(shewhart)} Shewhart cases")


if __name__ == "__main__":
    main()
