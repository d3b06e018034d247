"""docs/img/control-room.png: the control-room page during a replayed burst, in headless Chromium.

Usage: ``.venv/bin/python scripts/control_room_screenshot.py [--out PNG] [--speed X]``. A real
TSNet burst on pipe 9 of paper15 (seven meters, 0.2 s), written as a readings file with three
meters in trouble: ``8`` falls silent at t = 20 s, ``6``'s clock runs 3 s ahead, ``N8`` sends one
implausible reading at t = 100 s. ``burstloc monitor --web --replay-speed X`` plays it; the
page is captured after the decision, with the pointer on the first meter to alarm.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "web"))
sys.path.insert(0, str(ROOT / "python"))

METERS = ("N3", "N5", "N8", "2", "4", "6", "8")


def demo_feed(path: Path, config: object) -> None:
    """The burst's readings with the three meters' troubles (module docstring)."""
    from live_feed import burst_steps
    from web_browser import csv_lines

    steps = burst_steps(ROOT / "networks" / "paper15.inp", METERS, "9", sigma=0.003, after=240.0)
    out = []
    for line in csv_lines(steps, METERS):
        t, meter, value = line.split(",")
        time_s = float(t)
        if meter == "8" and time_s > 20:
            continue
        if meter == "6":
            t = f"{time_s + 3:.1f}"
        if meter == "N8" and time_s == 100.0:
            value = "9999.0"
        out.append(f"{t},{meter},{value}")
    path.write_text("\n".join(out) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "control-room.png")
    parser.add_argument("--speed", type=float, default=5.0)
    parser.add_argument("--at", type=float, default=130.0, help="reading time to capture, s")
    args = parser.parse_args()
    from selenium.webdriver.common.action_chains import ActionChains
    from web_browser import Monitor, chromium, page_state, wait_for

    from burstloc.experiments.calibrate import calibrate

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        network = ROOT / "networks" / "paper15.inp"
        config = calibrate(network, capture_intervals=(0.2,), noise_sigma=0.01, meters=METERS)
        config.save(folder / "paper15.json")
        demo_feed(folder / "demo.csv", config)
        monitor = Monitor(
            network,
            folder / "paper15.json",
            "--readings", str(folder / "demo.csv"), "--replay-speed", str(args.speed),
            "--web", "127.0.0.1:0", "--silent-after", "10", "--clock-tolerance", "1",
        )  # fmt: skip
        try:
            with chromium(folder / "chromium") as driver:
                driver.set_window_size(1600, 1000)
                driver.get(monitor.url)
                wait_for(lambda: page_state(driver).get("ready"), "ready")
                wait_for(lambda: page_state(driver).get("answer"), "the decision", 300)
                wait_for(
                    lambda: (
                        driver.execute_script("return rows.length && rows[rows.length - 1][0]")
                        >= args.at
                    ),
                    f"t = {args.at} s",
                    300,
                )
                meter = page_state(driver)["alarms"][0]["meter"]
                x, y = driver.execute_script(
                    "const i = net.nodeIndex[arguments[0]]; "
                    "return [sx(net.nodes.x[i]), sy(net.nodes.y[i])];",
                    meter,
                )
                canvas = driver.find_element("id", "map")
                size = canvas.size
                ActionChains(driver).move_to_element_with_offset(
                    canvas, int(x - size["width"] / 2), int(y - size["height"] / 2)
                ).perform()
                time.sleep(0.5)  # the tooltip and the panels' redraw
                args.out.parent.mkdir(parents=True, exist_ok=True)
                driver.save_screenshot(str(args.out))
        finally:
            monitor.stop()
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
