"""The exceptions burstloc raises.

Every error is a typed subclass of a built-in exception, so callers can catch precisely:

* :class:`ConfigError` (``ValueError``): a detector parameter is invalid; the message names
  the parameter and its value.
* :class:`InputError` (``ValueError``): a detector was fed bad input (a NaN, infinite or
  out-of-range sample, beyond +-1e100; a wrong dtype, shape or channel count; a snapshot holding
  a state no detector reaches); the message names the sample index, channel, argument or state
  field. The detector's state is left unchanged. Also raised for steps of readings whose feed
  file cannot be written (a step without one value per meter, a timestamp that is not finite).
* :class:`StreamError` (``InputError``): bad or out-of-order readings in a live stream.
* :class:`NetworkError` (``ValueError``): an unknown node or pipe, or a malformed INP file
  (with the file and line).
* :class:`SimulationError` (``RuntimeError``): the transient simulation (TSNet) failed.
* :class:`UnsteadyStartError` (``SimulationError``): the simulated heads moved before the event
  (the network does not start steady in the transient model); the message names the junction, the
  movement in metres and the network.
* :class:`SimulatorMissingError` (``SimulationError``): a command needs the simulator (TSNet,
  WNTR: the ``sim`` extra), which is not installed; the message says how to install it.
* :class:`OutputError` (``ValueError``): an output file or directory cannot be written (a
  missing or read-only directory, a directory where a file is expected, a full disk, a value
  JSON cannot hold); the message is ``cannot write PATH: reason``.

And one warning: :class:`DemandDrivenWarning` (``UserWarning``): EPANET cannot solve a network's
steady state pressure-driven, so it is solved demand-driven instead; the message names the
network and EPANET's error.

``ConfigError`` and ``InputError`` are defined by the native module (so the Rust code raises
them directly); the others are plain Python.
"""

from burstloc._core import ConfigError, InputError

__all__ = [
    "ConfigError",
    "DemandDrivenWarning",
    "InputError",
    "NetworkError",
    "OutputError",
    "SimulationError",
    "SimulatorMissingError",
    "StreamError",
    "UnsteadyStartError",
]


class StreamError(InputError):
    """Bad or out-of-order readings fed to a live stream."""


class DemandDrivenWarning(UserWarning):
    """EPANET cannot solve a network's steady state pressure-driven: it is solved demand-driven
    instead (every demand met in full, whatever the pressure); names the network and the error."""


class NetworkError(ValueError):
    """An unknown node or pipe, or a malformed network (INP) file, named with file and line."""


class SimulationError(RuntimeError):
    """The transient simulation (TSNet) failed for a scenario."""


class UnsteadyStartError(SimulationError):
    """A simulation's heads moved before its event: not a valid experiment.

    Args:
        network: the network file.
        junction: the junction whose pressure head moved most before the onset.
        movement: how far it moved from its initial head (m, absolute).
        time: when (s).
        onset: when the event begins (s).
        tolerance: the largest movement allowed (m).
    """

    def __init__(
        self,
        network: str,
        junction: str,
        movement: float,
        time: float,
        onset: float,
        tolerance: float,
    ) -> None:
        super().__init__(
            f"{network} does not start steady in the transient model: junction {junction!r} moved "
            f"{movement:.3g} m from its initial head by {time:.3g} s, before the event at "
            f"{onset:g} s (tolerance {tolerance:g} m): the transient model does not hold an "
            "element near it at its steady state (a valve, pump, tank or control): no burst on "
            "this network can be told from that movement, so none is simulated"
        )
        self.network = network
        self.junction = junction
        self.movement = movement
        self.time = time
        self.onset = onset


class SimulatorMissingError(SimulationError):
    """The simulator (TSNet, WNTR: the ``sim`` extra) is not installed or cannot be imported.

    Args:
        cause: the ``ImportError`` raised importing it; its message is kept in this one.
    """

    #: How to install the simulator (the end of the message when it is not installed).
    INSTALL = "pip install 'burstloc[sim]'"

    #: The simulator's own packages: when one of them is missing, the simulator is not installed;
    #: any other missing module is a dependency of theirs, named as such.
    PACKAGES = ("tsnet", "wntr")

    def __init__(self, cause: ImportError) -> None:
        name = cause.name
        if name is None or name.split(".")[0] in self.PACKAGES:
            message = f"this command needs the simulator, which is not installed ({cause}): "
            message += self.INSTALL
        elif name.split(".")[0] == "pkg_resources":
            message = (
                f"the simulator cannot be imported: WNTR 1.3 imports pkg_resources, which "
                f"setuptools 81 and later no longer provide ({cause}): pip install 'setuptools<81'"
            )
        else:
            message = (
                f"the simulator cannot be imported: its dependency {name!r} is missing ({cause}): "
                f"reinstall it with {self.INSTALL}"
            )
        super().__init__(message)
        self.package = name


class OutputError(ValueError):
    """An output cannot be written: ``cannot write PATH: reason`` (nothing was replaced)."""
