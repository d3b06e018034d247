//! The network as flat arrays (the time loop is in `step`).

use crate::Error;

/// A pipe's constants, as `burstloc.sim.moc_layout` computes them in TSNet's order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pipe {
    /// First point of the pipe in the flat arrays.
    pub offset: usize,
    /// Number of reaches: the pipe has `n + 1` points.
    pub n: usize,
    /// `g / a`.
    pub ga: f64,
    /// `a / g`.
    pub ag: f64,
    /// `g / a * dt`.
    pub gadt: f64,
    /// The pipe's slope term.
    pub theta: f64,
    /// Steady friction `f * dt / 2 / D`.
    pub cf: f64,
    /// Steady friction `f * dt / (2 D)`.
    pub cf2: f64,
    /// `pi D^2 / 4`.
    pub area: f64,
    /// `pi / 4 D^2`.
    pub area_dead: f64,
}

/// A pipe end: its point, the point next to it in the same pipe, the pipe.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct End {
    /// The end's point.
    pub out: usize,
    /// The point next to it.
    pub near: usize,
    /// The pipe's index.
    pub pipe: usize,
}

/// A pipe end at a junction (TSNet's `add_leakage`).
#[derive(Debug, Clone, PartialEq)]
pub struct Junction {
    /// The end.
    pub end: End,
    /// The junction's node index.
    pub node: usize,
    /// The own pipe's sign: -1 at its start, 1 at its end.
    pub sign: f64,
    /// The junction equation's constant `b`.
    pub b: f64,
    /// `b` squared as the C library's `pow` computes it ([`crate::pow2`]).
    pub b2: f64,
    /// Its entries in [`Model::contributions`].
    pub contributions: core::ops::Range<usize>,
}

/// One pipe meeting at a junction end, in its sum's order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contribution {
    /// The point next to the junction in that pipe.
    pub index: usize,
    /// That pipe.
    pub pipe: usize,
    /// Its sign.
    pub sign: f64,
    /// `np.dot`'s lane (0..4) it is added in.
    pub lane: usize,
}

/// A dead end: a junction ending one pipe (TSNet's `dead_end`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadEnd {
    /// The end.
    pub end: End,
    /// The node's index.
    pub node: usize,
    /// The lowest head without demand.
    pub floor: f64,
    /// At the pipe's start.
    pub at_start: bool,
}

/// A reservoir or tank ending one pipe, holding its head (TSNet's `rev_end`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reservoir {
    /// The end.
    pub end: End,
    /// The head held.
    pub head: f64,
    /// 1 at the pipe's start, -1 at its end.
    pub side: f64,
}

/// A valve leading nowhere, holding a flow given per step (TSNet's `valve_end`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValveEnd {
    /// The end.
    pub end: End,
    /// 1 at the pipe's start, -1 at its end.
    pub side: f64,
}

/// What sits at an [`Element`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ElementKind {
    /// A valve between pipes (TSNet's `valve_node`); series column 0: the inverse loss.
    Valve,
    /// A pump between pipes (TSNet's `pump_node`), on its suction side or not; series columns:
    /// the curve's `a, b, c`.
    Pump {
        /// The pipe end is on the pump's suction side.
        suction: bool,
    },
    /// A pump drawing from a reservoir (TSNet's `source_pump`) with the sump's head; series
    /// columns: the curve's `a, b, c`.
    Source {
        /// The sump's head.
        sump: f64,
    },
}

/// A pipe end at a pump or valve: TSNet's characteristic `C1` (upstream) and `C2`
/// (downstream) from the points `link1` and `link2` (point, pipe, sign).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Element {
    /// What it is.
    pub kind: ElementKind,
    /// The end's point.
    pub out: usize,
    /// The end is its pipe's start (TSNet's `nn == 0`).
    pub at_start: bool,
    /// `C1`'s point, pipe and sign (unused by a source pump).
    pub link1: (usize, usize, f64),
    /// `C2`'s point, pipe and sign.
    pub link2: (usize, usize, f64),
}

/// The whole model. Per-step series are row-major `steps x count` (elements:
/// `steps x count x 3`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Model {
    /// Number of time steps, the first being the initial state.
    pub steps: usize,
    /// Every pipe.
    pub pipes: Vec<Pipe>,
    /// Initial heads of every point.
    pub h0: Vec<f64>,
    /// Initial velocities of every point.
    pub v0: Vec<f64>,
    /// Per node: the emitter coefficient at the start (a burst's is replaced per step).
    pub emitter: Vec<f64>,
    /// Per node: the demand coefficient (a pulse's is scaled per step).
    pub demand: Vec<f64>,
    /// Per node: the elevation.
    pub elevation: Vec<f64>,
    /// Pipe ends at junctions.
    pub junctions: Vec<Junction>,
    /// The pipes meeting at junction ends.
    pub contributions: Vec<Contribution>,
    /// Dead ends.
    pub dead_ends: Vec<DeadEnd>,
    /// Reservoirs and tanks.
    pub reservoirs: Vec<Reservoir>,
    /// Valves leading nowhere.
    pub valve_ends: Vec<ValveEnd>,
    /// Their velocities per step.
    pub valve_series: Vec<f64>,
    /// Pumps and valves.
    pub elements: Vec<Element>,
    /// Their parameters per step.
    pub element_series: Vec<f64>,
    /// Nodes whose emitter coefficient is given per step (bursts).
    pub bursts: Vec<usize>,
    /// Their coefficients per step.
    pub burst_series: Vec<f64>,
    /// Nodes whose demand is scaled per step by `1 + pulse` (demand pulses).
    pub pulses: Vec<usize>,
    /// Their pulses per step.
    pub pulse_series: Vec<f64>,
    /// The points whose heads are recorded.
    pub record: Vec<usize>,
}

/// What [`Model::run`] produces.
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    /// Heads of the recorded points, row-major `steps x record`.
    pub heads: Vec<f64>,
    /// Per junction end: the steps its equation had no real root.
    pub junction_failed: Vec<u64>,
    /// Per dead end: the steps its equation had no real root.
    pub dead_failed: Vec<u64>,
    /// Per element: steps without a real root, reverse flows stopped by the pump's check
    /// valve, negative head gains bypassed (TSNet's three warnings).
    pub element_warnings: Vec<[u64; 3]>,
}

fn check(what: &str, i: usize, index: usize, size: usize) -> Result<(), Error> {
    if index < size {
        Ok(())
    } else {
        Err(Error(format!(
            "{what} {i}: index {index} out of range 0..{size}"
        )))
    }
}

impl Model {
    /// Checks that every index is in range and every series long enough.
    ///
    /// # Errors
    /// [`Error`] naming the first array entry that does not fit.
    pub fn validate(&self) -> Result<(), Error> {
        let points = self.h0.len();
        if self.v0.len() != points {
            return Err(Error(format!(
                "h0 and v0 differ in length: {} and {}",
                points,
                self.v0.len()
            )));
        }
        let nodes = self.emitter.len();
        if self.demand.len() != nodes || self.elevation.len() != nodes {
            return Err(Error(
                "emitter, demand and elevation differ in length".into(),
            ));
        }
        if self.steps == 0 {
            return Err(Error("steps must be at least 1".into()));
        }
        let pipes = self.pipes.len();
        for (i, p) in self.pipes.iter().enumerate() {
            if p.n == 0 || p.offset + p.n >= points {
                return Err(Error(format!(
                    "pipe {i}: points {}..={} out of range 0..{points}",
                    p.offset,
                    p.offset + p.n
                )));
            }
        }
        let end = |what: &str, i: usize, e: &End| -> Result<(), Error> {
            check(what, i, e.out, points)?;
            check(what, i, e.near, points)?;
            check(what, i, e.pipe, pipes)
        };
        for (i, j) in self.junctions.iter().enumerate() {
            end("junction end", i, &j.end)?;
            check("junction end", i, j.node, nodes)?;
            if j.contributions.start > j.contributions.end
                || j.contributions.end > self.contributions.len()
            {
                return Err(Error(format!(
                    "junction end {i}: contributions {:?} out of range 0..{}",
                    j.contributions,
                    self.contributions.len()
                )));
            }
        }
        for (i, c) in self.contributions.iter().enumerate() {
            check("contribution", i, c.index, points)?;
            check("contribution", i, c.pipe, pipes)?;
            check("contribution lane", i, c.lane, 4)?;
        }
        for (i, d) in self.dead_ends.iter().enumerate() {
            end("dead end", i, &d.end)?;
            check("dead end", i, d.node, nodes)?;
        }
        for (i, r) in self.reservoirs.iter().enumerate() {
            end("reservoir end", i, &r.end)?;
        }
        for (i, v) in self.valve_ends.iter().enumerate() {
            end("valve end", i, &v.end)?;
        }
        for (i, e) in self.elements.iter().enumerate() {
            check("element", i, e.out, points)?;
            check("element", i, e.link1.0, points)?;
            check("element", i, e.link1.1, pipes)?;
            check("element", i, e.link2.0, points)?;
            check("element", i, e.link2.1, pipes)?;
        }
        for (i, &b) in self.bursts.iter().enumerate() {
            check("burst", i, b, nodes)?;
        }
        for (i, &b) in self.pulses.iter().enumerate() {
            check("pulse", i, b, nodes)?;
        }
        for (i, &r) in self.record.iter().enumerate() {
            check("record", i, r, points)?;
        }
        let series = [
            (
                "valve_series",
                self.valve_series.len(),
                self.valve_ends.len(),
            ),
            (
                "element_series",
                self.element_series.len(),
                3 * self.elements.len(),
            ),
            ("burst_series", self.burst_series.len(), self.bursts.len()),
            ("pulse_series", self.pulse_series.len(), self.pulses.len()),
        ];
        for (name, len, width) in series {
            if len != self.steps * width {
                return Err(Error(format!(
                    "{name} must hold {} steps x {width} values, got {len}",
                    self.steps
                )));
            }
        }
        Ok(())
    }
}
