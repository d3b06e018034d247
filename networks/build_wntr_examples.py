"""Build the two extra study networks from example INP files that ship with WNTR 1.3.2.

* ``todini6.inp``: WNTR's ``Todini_Fig2_solA_CMH.inp`` (one reservoir, 6 junctions, 8 pipes;
  Todini's two-loop design example), copied byte for byte: TSNet 0.3.1 simulates it as is. Being
  a third-party file it is not committed: ``make setup`` writes it from the installed WNTR.
* ``awumah11.inp``: WNTR's ``Awumah_layout1.inp`` (one reservoir, 11 junctions, 12 pipes, one
  loop and four branches) is a layout only (zero demands, a reservoir at head 0). We keep its
  topology, pipe lengths (1000 ft), diameters (12 in) and Hazen-Williams C (100) and give it
  hydraulics of our own: its source node 1 becomes a junction fed by a new reservoir R1 (head
  60 m) through a new pipe P0 (100 m, 500 mm; TSNet 0.3.1 needs a reservoir at the end of a
  single pipe), every junction at elevation 0 with a base demand of 5 L/s, in LPS units.

Run from the repository root::

    python networks/build_wntr_examples.py           # rewrite both files
    python networks/build_wntr_examples.py --check   # exit 1 if a shipped file differs

Both sources are under WNTR's Revised BSD licence (``wntr-1.3.2.dist-info/LICENSE.md``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: Hydraulics given to the Awumah layout (SI: m, m³/s).
AWUMAH_RESERVOIR_HEAD = 60.0
AWUMAH_DEMAND = 0.005
#: The supply pipe from the new reservoir R1 to the layout's source node 1 (m, mm).
SUPPLY_LENGTH = 100.0
SUPPLY_DIAMETER_MM = 500.0


def _wntr_examples() -> Path:
    import wntr

    return Path(wntr.__file__).resolve().parent / "tests" / "networks_for_testing"


def build_todini() -> bytes:
    """Return the bytes of ``todini6.inp`` (WNTR's file, unchanged)."""
    return (_wntr_examples() / "Todini_Fig2_solA_CMH.inp").read_bytes()


def build_awumah() -> bytes:
    """Return the bytes of ``awumah11.inp`` (WNTR's layout with our hydraulics)."""
    import wntr

    wn = wntr.network.WaterNetworkModel(str(_wntr_examples() / "Awumah_layout1.inp"))
    lines = [
        "; awumah11.inp: written by networks/build_wntr_examples.py from WNTR 1.3.2's",
        "; Awumah_layout1.inp (see networks/README.md)",
        "[TITLE]",
        "Awumah layout 1 with burstloc's hydraulics",
        "",
        "[JUNCTIONS]",
        ";ID  Elev  Demand",
    ]
    # The layout's source node "1" becomes a junction fed by reservoir R1 through pipe P0:
    # TSNet 0.3.1 needs a reservoir at the end of a single pipe.
    lines.append(" 1  0  0")
    for name, _ in wn.junctions():
        lines.append(f" {name}  0  {AWUMAH_DEMAND * 1000:g}")
    lines += ["", "[RESERVOIRS]", ";ID  Head", f" R1  {AWUMAH_RESERVOIR_HEAD:g}", ""]
    lines += ["[PIPES]", ";ID  Node1  Node2  Length  Diameter  Roughness  MinorLoss  Status"]
    lines.append(f" P0  R1  1  {SUPPLY_LENGTH:g}  {SUPPLY_DIAMETER_MM:g}  100  0  Open")
    for name, pipe in wn.pipes():
        lines.append(
            f" {name}  {pipe.start_node_name}  {pipe.end_node_name}  {pipe.length:.4f}  "
            f"{pipe.diameter * 1000:.2f}  {pipe.roughness:g}  0  Open"
        )
    lines += ["", "[OPTIONS]", " Units  LPS", " Headloss  H-W", "", "[COORDINATES]"]
    for name, node in wn.nodes():
        x, y = node.coordinates
        lines.append(f" {name}  {x:g}  {y:g}")
    x, y = wn.get_node("1").coordinates
    lines += [f" R1  {x - 1:g}  {y:g}", "", "[END]", ""]
    return "\n".join(lines).encode()


BUILDERS = {"todini6.inp": build_todini, "awumah11.inp": build_awumah}


def main(argv: list[str] | None = None) -> int:
    """Write (or with ``--check`` compare) the derived networks; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare instead of writing")
    args = parser.parse_args(argv)
    status = 0
    for name, build in BUILDERS.items():
        data = build()
        path = HERE / name
        if args.check:
            if not path.exists() or path.read_bytes() != data:
                print(f"{path} differs from what {Path(__file__).name} writes", file=sys.stderr)
                status = 1
        else:
            path.write_bytes(data)
            print(f"wrote {path}")
    return status


if __name__ == "__main__":
    sys.exit(main())
