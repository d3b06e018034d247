"""burstloc: real-time pipe-burst localization in water distribution networks.

The detectors are implemented in Rust (``cpd-core``) and exposed here:

* :class:`Cusum` and :class:`Shewhart`: streaming change-point detectors, one sample per
  ``update(x)`` call, or a whole NumPy array per ``update_many(x)`` call;
* :class:`DetectorBank`: one detector per pressure sensor, advanced a time step at a time;
* :func:`detect_cusum` and :func:`detect_shewhart`: the batch reference algorithms (TSNet's
  ``detect_cusum`` and the paper's Algorithm 2);
* :class:`Alarm`: what the detectors report;
* :class:`ConfigError` and :class:`InputError` (both ``ValueError``): bad parameters and bad
  input, respectively.

Importing ``burstloc`` loads only the native module: the simulation stack (TSNet, WNTR) is
imported by ``burstloc.sim.tsnet`` when needed.
"""

from burstloc._core import (
    Alarm,
    Cusum,
    DetectorBank,
    Shewhart,
    __version__,
    detect_cusum,
    detect_shewhart,
)
from burstloc.exceptions import ConfigError, InputError

__all__ = [
    "Alarm",
    "ConfigError",
    "Cusum",
    "DetectorBank",
    "InputError",
    "Shewhart",
    "__version__",
    "detect_cusum",
    "detect_shewhart",
]
