"""A small network with short connector pipes, written by the tests that need one."""

from __future__ import annotations

__all__ = ["CONNECTOR_INP", "METERS"]

#: Pipes of 30 to 60 m, so that TSNet runs it as it is (a 0.125 ms step) in seconds. R1 feeds
#: J1; a 0.3 m connector C1 joins J1 to the branch junction J2 (three pipes); a 0.5 m connector
#: C2 joins J4 to J5 (no demand, two pipes: a series merge), which feeds J6.
CONNECTOR_INP = """\
[JUNCTIONS]
;ID  Elev  Demand
 J1  0     10
 J2  0     0
 J3  0     20
 J4  0     15
 J5  0     0
 J6  0     25

[RESERVOIRS]
 R1  60

[PIPES]
;ID  Node1  Node2  Length  Diameter  Roughness  MinorLoss  Status
 P1  R1     J1     50      300       120        0          Open
 C1  J1     J2     0.3     300       120        0          Open
 P2  J2     J3     40      200       110        0          Open
 P3  J2     J4     60      250       120        0          Open
 P4  J3     J4     30      150       100        0          Open
 C2  J4     J5     0.5     200       120        0          Open
 P5  J5     J6     35      150       110        0          Open

[OPTIONS]
 Units     LPS
 Headloss  H-W

[END]
"""


#: The junctions the tests meter (J2, a branch point, and J5, a series point, carry none).
METERS = ["J1", "J3", "J4", "J6"]
