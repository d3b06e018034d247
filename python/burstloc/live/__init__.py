"""The live loop: readings in, burst decisions and health out. Never imports
:mod:`burstloc.sim`, WNTR or TSNet.

* :mod:`~burstloc.live.parse`: CSV lines and MQTT payloads to readings, bad input named;
* :mod:`~burstloc.live.plausible`: each meter's believable readings;
* :mod:`~burstloc.live.health`: per-meter health, plausible range, clock offsets, silence;
* :mod:`~burstloc.live.feeds`: raw readings assembled into complete time steps;
* :mod:`~burstloc.live.windows`: complete steps into the localization windows of the paper's loop;
* :mod:`~burstloc.live.subset`: the localizers restricted to the meters that report, and the
  meters taking part;
* :mod:`~burstloc.live.decision`: a decision as the monitor reports it;
* :mod:`~burstloc.live.monitor`: the detector bank, history and localizer over those steps,
  built from the stored configuration (no hydraulic model runs);
* :mod:`~burstloc.live.history`: the monitor's recent readings, in one ring array;
* :mod:`~burstloc.live.arming`: the monitor's hold-off after a decision and its re-arming;
* :mod:`~burstloc.live.monitor_state`: the monitor's state across a restart;
* :mod:`~burstloc.live.loop`: the loop that wires them and never stops on bad data;
* :mod:`~burstloc.live.reporter`: its messages for the operator, rate-limited;
* :mod:`~burstloc.live.state`: the saved state (atomic, versioned, bound to its setup);
* :mod:`~burstloc.live.mqtt`: readings from a broker, decisions and health to it;
* :mod:`~burstloc.live.paper_locator`: the paper's real-time loop (windows, detector, rules).

The public way to feed readings to a :class:`~burstloc.live.monitor.BurstMonitor` (also in the
package façade, ``burstloc.StepFeed`` ...; ``docs/api.md`` has an example): :func:`parse_lines`
reads CSV lines into readings, a :class:`StepFeed` assembles them into complete time steps, and
``BurstMonitor.push(step)`` answers. :class:`~burstloc.live.loop.LiveLoop` adds meter health,
reports and a saved state (what ``burstloc monitor`` runs).
"""

from burstloc.live.feeds import StepFeed, StreamStats
from burstloc.live.parse import BadReading, parse_lines

__all__ = ["BadReading", "StepFeed", "StreamStats", "parse_lines"]
