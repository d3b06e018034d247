//! `moc_run`: the MOC time loop of `moc-core` over a network laid out by
//! `burstloc.sim.moc_layout`, for `burstloc.sim.moc_rust`.

use numpy::ndarray::Array2;
use numpy::{
    Element, IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::errors::input_err;

/// The values of a 1-D array of `T` (`cols == None`) or the rows of a 2-D array of `T` with
/// `cols` columns, in C order, or an `InputError` naming `name`.
fn table<T: Element + Copy>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    cols: Option<usize>,
) -> PyResult<Vec<T>> {
    let kind = core::any::type_name::<T>();
    let wanted = match cols {
        None => format!("{name} must be a 1-D numpy array of {kind}"),
        Some(c) => format!("{name} must be a 2-D numpy array of {kind} with {c} columns"),
    };
    let shape = obj
        .cast::<PyUntypedArray>()
        .map(|a| a.shape().to_vec())
        .map_err(|_| input_err(format!("{wanted}, got {}", type_name(obj))))?;
    let values: Option<Vec<T>> = match cols {
        None => obj
            .cast::<PyArray1<T>>()
            .ok()
            .and_then(|a| a.try_readonly().ok())
            .map(|a| a.as_array().iter().copied().collect()),
        Some(c) if shape.len() == 2 && shape[1] == c => obj
            .cast::<PyArray2<T>>()
            .ok()
            .and_then(|a| a.try_readonly().ok())
            .map(|a| a.as_array().iter().copied().collect()),
        Some(_) => None,
    };
    values.ok_or_else(|| input_err(format!("{wanted}, got shape {shape:?} of {}", dtype(obj))))
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "?".to_owned(), |s| s.to_string())
}

fn dtype(obj: &Bound<'_, PyAny>) -> String {
    obj.cast::<PyUntypedArray>()
        .ok()
        .and_then(|a| a.dtype().str().ok().map(|s| s.to_string()))
        .unwrap_or_else(|| "?".to_owned())
}

/// An index read from an int64 array: negative ones are refused.
fn index(value: i64, name: &str) -> PyResult<usize> {
    usize::try_from(value).map_err(|_| input_err(format!("{name} holds a negative index {value}")))
}

fn end(row: &[i64], name: &str) -> PyResult<moc_core::End> {
    Ok(moc_core::End {
        out: index(row[0], name)?,
        near: index(row[1], name)?,
        pipe: index(row[2], name)?,
    })
}

type Run<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyArray2<u64>>,
);

/// Runs TSNet's MOC time loop (steady friction) over a network laid out as arrays
/// (`burstloc.sim.moc_rust` builds them from a `burstloc.sim.moc_layout.Layout`).
///
/// Returns `(heads (steps, record), junction_failed, dead_failed, element_warnings (K, 3))`:
/// the heads of the recorded points at every step, and per junction end, dead end and pump or
/// valve the number of steps TSNet would have warned of (no real root; for elements also a
/// pump's reverse flow stopped, negative head gain bypassed).
///
/// Raises `InputError` when an array has the wrong dtype or shape, an index is out of range or
/// a per-step series has fewer than `steps` rows.
#[pyfunction]
#[pyo3(signature = (
    *, steps, pipe_points, pipes, h0, v0, nodes, junctions, junction_values, contributions,
    contribution_signs, dead_ends, dead_floors, reservoirs, reservoir_values, valve_ends,
    valve_sides, valve_series, elements, element_values, element_series, bursts, burst_series,
    pulses, pulse_series, record
))]
#[allow(clippy::too_many_arguments)]
pub fn moc_run<'py>(
    py: Python<'py>,
    steps: usize,
    pipe_points: &Bound<'py, PyAny>,
    pipes: &Bound<'py, PyAny>,
    h0: &Bound<'py, PyAny>,
    v0: &Bound<'py, PyAny>,
    nodes: &Bound<'py, PyAny>,
    junctions: &Bound<'py, PyAny>,
    junction_values: &Bound<'py, PyAny>,
    contributions: &Bound<'py, PyAny>,
    contribution_signs: &Bound<'py, PyAny>,
    dead_ends: &Bound<'py, PyAny>,
    dead_floors: &Bound<'py, PyAny>,
    reservoirs: &Bound<'py, PyAny>,
    reservoir_values: &Bound<'py, PyAny>,
    valve_ends: &Bound<'py, PyAny>,
    valve_sides: &Bound<'py, PyAny>,
    valve_series: &Bound<'py, PyAny>,
    elements: &Bound<'py, PyAny>,
    element_values: &Bound<'py, PyAny>,
    element_series: &Bound<'py, PyAny>,
    bursts: &Bound<'py, PyAny>,
    burst_series: &Bound<'py, PyAny>,
    pulses: &Bound<'py, PyAny>,
    pulse_series: &Bound<'py, PyAny>,
    record: &Bound<'py, PyAny>,
) -> PyResult<Run<'py>> {
    let mut model = moc_core::Model {
        steps,
        ..moc_core::Model::default()
    };
    let points: Vec<i64> = table(pipe_points, "pipe_points", Some(2))?;
    let constants: Vec<f64> = table(pipes, "pipes", Some(8))?;
    if points.len() / 2 != constants.len() / 8 {
        return Err(input_err(
            "pipe_points and pipes must have one row per pipe".to_owned(),
        ));
    }
    for (pt, c) in points.chunks_exact(2).zip(constants.chunks_exact(8)) {
        model.pipes.push(moc_core::Pipe {
            offset: index(pt[0], "pipe_points")?,
            n: index(pt[1], "pipe_points")?,
            ga: c[0],
            ag: c[1],
            gadt: c[2],
            theta: c[3],
            cf: c[4],
            cf2: c[5],
            area: c[6],
            area_dead: c[7],
        });
    }
    model.h0 = table(h0, "h0", None)?;
    model.v0 = table(v0, "v0", None)?;
    let node_values: Vec<f64> = table(nodes, "nodes", Some(3))?;
    for row in node_values.chunks_exact(3) {
        model.emitter.push(row[0]);
        model.demand.push(row[1]);
        model.elevation.push(row[2]);
    }
    let junction_rows: Vec<i64> = table(junctions, "junctions", Some(4))?;
    let junction_vals: Vec<f64> = table(junction_values, "junction_values", Some(2))?;
    let contribution_rows: Vec<i64> = table(contributions, "contributions", Some(4))?;
    let signs: Vec<f64> = table(contribution_signs, "contribution_signs", None)?;
    if junction_rows.len() / 4 != junction_vals.len() / 2
        || contribution_rows.len() / 4 != signs.len()
    {
        return Err(input_err(
            "junctions and junction_values, contributions and contribution_signs must have \
             as many rows"
                .to_owned(),
        ));
    }
    let mut start = 0;
    for (e, (row, vals)) in junction_rows
        .chunks_exact(4)
        .zip(junction_vals.chunks_exact(2))
        .enumerate()
    {
        let mut stop = start;
        while stop < signs.len() && contribution_rows[4 * stop] == e as i64 {
            stop += 1;
        }
        model.junctions.push(moc_core::Junction {
            end: end(row, "junctions")?,
            node: index(row[3], "junctions")?,
            sign: vals[0],
            b: vals[1],
            b2: moc_core::pow2(vals[1]),
            contributions: start..stop,
        });
        start = stop;
    }
    if start != signs.len() {
        return Err(input_err(
            "contributions must be grouped by junction end, in the junctions' order".to_owned(),
        ));
    }
    for (row, sign) in contribution_rows.chunks_exact(4).zip(&signs) {
        model.contributions.push(moc_core::Contribution {
            index: index(row[1], "contributions")?,
            pipe: index(row[2], "contributions")?,
            sign: *sign,
            lane: index(row[3], "contributions")?,
        });
    }
    let dead_rows: Vec<i64> = table(dead_ends, "dead_ends", Some(5))?;
    let floors: Vec<f64> = table(dead_floors, "dead_floors", None)?;
    if dead_rows.len() / 5 != floors.len() {
        return Err(input_err(
            "dead_ends and dead_floors must have as many rows".to_owned(),
        ));
    }
    for (row, floor) in dead_rows.chunks_exact(5).zip(floors) {
        model.dead_ends.push(moc_core::DeadEnd {
            end: end(row, "dead_ends")?,
            node: index(row[3], "dead_ends")?,
            floor,
            at_start: row[4] != 0,
        });
    }
    let rev_rows: Vec<i64> = table(reservoirs, "reservoirs", Some(3))?;
    let rev_vals: Vec<f64> = table(reservoir_values, "reservoir_values", Some(2))?;
    if rev_rows.len() / 3 != rev_vals.len() / 2 {
        return Err(input_err(
            "reservoirs and reservoir_values must have as many rows".to_owned(),
        ));
    }
    for (row, vals) in rev_rows.chunks_exact(3).zip(rev_vals.chunks_exact(2)) {
        model.reservoirs.push(moc_core::Reservoir {
            end: end(row, "reservoirs")?,
            head: vals[0],
            side: vals[1],
        });
    }
    let valve_rows: Vec<i64> = table(valve_ends, "valve_ends", Some(3))?;
    let sides: Vec<f64> = table(valve_sides, "valve_sides", None)?;
    if valve_rows.len() / 3 != sides.len() {
        return Err(input_err(
            "valve_ends and valve_sides must have as many rows".to_owned(),
        ));
    }
    for (row, side) in valve_rows.chunks_exact(3).zip(sides) {
        model.valve_ends.push(moc_core::ValveEnd {
            end: end(row, "valve_ends")?,
            side,
        });
    }
    model.valve_series = table(valve_series, "valve_series", Some(model.valve_ends.len()))?;
    let element_rows: Vec<i64> = table(elements, "elements", Some(8))?;
    let element_vals: Vec<f64> = table(element_values, "element_values", Some(3))?;
    if element_rows.len() / 8 != element_vals.len() / 3 {
        return Err(input_err(
            "elements and element_values must have as many rows".to_owned(),
        ));
    }
    for (row, vals) in element_rows
        .chunks_exact(8)
        .zip(element_vals.chunks_exact(3))
    {
        let kind = match row[0] {
            0 => moc_core::ElementKind::Valve,
            1 => moc_core::ElementKind::Pump {
                suction: row[7] != 0,
            },
            2 => moc_core::ElementKind::Source { sump: vals[2] },
            other => {
                return Err(input_err(format!(
                    "elements: kind {other} is none of 0 (valve), 1 (pump), 2 (source pump)"
                )))
            }
        };
        model.elements.push(moc_core::Element {
            kind,
            out: index(row[1], "elements")?,
            at_start: row[2] != 0,
            link1: (
                index(row[3], "elements")?,
                index(row[4], "elements")?,
                vals[0],
            ),
            link2: (
                index(row[5], "elements")?,
                index(row[6], "elements")?,
                vals[1],
            ),
        });
    }
    model.element_series = table(
        element_series,
        "element_series",
        Some(3 * model.elements.len()),
    )?;
    model.bursts = table::<i64>(bursts, "bursts", None)?
        .into_iter()
        .map(|i| index(i, "bursts"))
        .collect::<PyResult<_>>()?;
    model.burst_series = table(burst_series, "burst_series", Some(model.bursts.len()))?;
    model.pulses = table::<i64>(pulses, "pulses", None)?
        .into_iter()
        .map(|i| index(i, "pulses"))
        .collect::<PyResult<_>>()?;
    model.pulse_series = table(pulse_series, "pulse_series", Some(model.pulses.len()))?;
    model.record = table::<i64>(record, "record", None)?
        .into_iter()
        .map(|i| index(i, "record"))
        .collect::<PyResult<_>>()?;
    let width = model.record.len();
    let out = py
        .detach(|| model.run())
        .map_err(|e| input_err(e.to_string()))?;
    let heads = Array2::from_shape_vec((steps, width), out.heads)
        .map_err(|e| input_err(format!("heads: {e}")))?;
    let warnings: Vec<u64> = out.element_warnings.iter().flatten().copied().collect();
    let warnings = Array2::from_shape_vec((out.element_warnings.len(), 3), warnings)
        .map_err(|e| input_err(format!("element warnings: {e}")))?;
    Ok((
        heads.into_pyarray(py),
        out.junction_failed.into_pyarray(py),
        out.dead_failed.into_pyarray(py),
        warnings.into_pyarray(py),
    ))
}
