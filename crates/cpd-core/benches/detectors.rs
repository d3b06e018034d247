//! Per-sample cost of the streaming detectors and banks.
//!
//! `cargo bench -p cpd-core -- --measurement-time 2 --warm-up-time 1`
//!
//! Time is the benchmark thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`), not wall time: the
//! 2-core machines are shared, and other processes would otherwise inflate the figures.
//! Set `CPD_BENCH_WALL=1` to measure wall time instead.
//!
//! Inputs are **fresh** seeded pressure-like traces (see `common/traces.rs`): heads of 200 m with
//! near-Gaussian sensor noise (a sum of 4 uniforms) of σ = 0.05 m and a burst (a 0.5–2 m drop with damped ringing) every
//! ~50 000 samples, detectors at thresholds calibrated for that noise (CUSUM 0.3 m, drift
//! 0.01 m; Shewhart 3σ and 0.2 m). Every timed iteration gets a trace it has never seen (a new
//! seed; generation is outside the timing), so the branch predictor cannot learn the data. The
//! `replayed/` group keeps the old measurement (one 100 000-sample trace fed again and again)
//! for comparison only: it flatters data-dependent branches.

use std::hint::black_box;

use cpd_core::{Bank, ChannelAlarm, CusumBank, CusumConfig, Shewhart, ShewhartBank};
use cpu_time::ThreadTime;
use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{
    criterion_group, criterion_main, BatchSize, BenchmarkGroup, BenchmarkId, Criterion, Throughput,
};

#[path = "common/traces.rs"]
mod traces;
use traces::*;

/// Thread CPU time in nanoseconds (or wall time with `CPD_BENCH_WALL=1`).
struct CpuTime {
    wall: bool,
}

impl Measurement for CpuTime {
    type Intermediate = (Option<ThreadTime>, Option<std::time::Instant>);
    type Value = f64;

    fn start(&self) -> Self::Intermediate {
        if self.wall {
            (None, Some(std::time::Instant::now()))
        } else {
            (Some(ThreadTime::now()), None)
        }
    }
    fn end(&self, i: Self::Intermediate) -> f64 {
        match i {
            (Some(t), _) => t.elapsed().as_nanos() as f64,
            (_, Some(t)) => t.elapsed().as_nanos() as f64,
            _ => unreachable!(),
        }
    }
    fn add(&self, a: &f64, b: &f64) -> f64 {
        a + b
    }
    fn zero(&self) -> f64 {
        0.0
    }
    fn to_f64(&self, v: &f64) -> f64 {
        *v
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        // Values are nanoseconds, exactly as for wall time.
        WallTime.formatter()
    }
}

fn config() -> Criterion<CpuTime> {
    let wall = std::env::var_os("CPD_BENCH_WALL").is_some_and(|v| v == "1");
    Criterion::default().with_measurement(CpuTime { wall })
}

const CUSUMS: [(&str, f64); 2] = [("cusum", CUSUM_DRIFT), ("cusum_nodrift", 0.0)];

/// One detector per sample (`update`) and per slice (`update_slice`), fresh data each time.
fn single_channel(c: &mut Criterion<CpuTime>) {
    let mut traces = Traces::new(1);
    let mut group = c.benchmark_group("update");
    group.throughput(Throughput::Elements(SAMPLES as u64));
    for (name, drift) in CUSUMS {
        let mut det = cusum(drift);
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || traces.heads(SAMPLES),
                |x| {
                    let mut alarms = 0u32;
                    for &v in x.iter() {
                        alarms += det.update(black_box(v)).unwrap().is_some() as u32;
                    }
                    alarms
                },
                BatchSize::LargeInput,
            )
        });
    }
    for w in WINDOWS {
        let mut det = Shewhart::new(shewhart_config(w)).unwrap();
        group.bench_with_input(BenchmarkId::new("shewhart", w), &w, |b, _| {
            b.iter_batched_ref(
                || traces.heads(SAMPLES),
                |x| {
                    let mut alarms = 0u32;
                    for &v in x.iter() {
                        alarms += det.update(black_box(v)).unwrap().is_some() as u32;
                    }
                    alarms
                },
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();

    // The batch entry point (what the Python `update_many` calls): state stays in registers.
    let mut group = c.benchmark_group("update_slice");
    group.throughput(Throughput::Elements(SAMPLES as u64));
    let mut out = Vec::with_capacity(SAMPLES);
    for (name, drift) in CUSUMS {
        let mut det = cusum(drift);
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || traces.heads(SAMPLES),
                |x| {
                    out.clear();
                    det.update_slice(black_box(x), &mut out).unwrap();
                    out.len()
                },
                BatchSize::LargeInput,
            )
        });
    }
    // The same work in slices too short for the segments (under 512 samples): the sequential
    // kernel, the alternative the segments are measured against in the same run.
    let mut det = cusum(CUSUM_DRIFT);
    group.bench_function("cusum_sequential_in_256_sample_slices", |b| {
        b.iter_batched_ref(
            || traces.heads(SAMPLES),
            |x| {
                out.clear();
                for part in black_box(&x[..]).chunks(256) {
                    det.update_slice(part, &mut out).unwrap();
                }
                out.len()
            },
            BatchSize::LargeInput,
        )
    });
    for w in WINDOWS {
        let mut det = Shewhart::new(shewhart_config(w)).unwrap();
        group.bench_with_input(BenchmarkId::new("shewhart", w), &w, |b, _| {
            b.iter_batched_ref(
                || traces.heads(SAMPLES),
                |x| {
                    out.clear();
                    det.update_slice(black_box(x), &mut out).unwrap();
                    out.len()
                },
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

/// The old measurement, kept for comparison and labelled: one trace replayed every iteration.
fn replayed(c: &mut Criterion<CpuTime>) {
    let x = Traces::new(0).heads(SAMPLES);
    let mut group = c.benchmark_group("replayed_one_trace");
    group.throughput(Throughput::Elements(SAMPLES as u64));
    let mut det = cusum(CUSUM_DRIFT);
    group.bench_function("update/cusum", |b| {
        b.iter(|| {
            let mut alarms = 0u32;
            for &v in &x {
                alarms += det.update(black_box(v)).unwrap().is_some() as u32;
            }
            alarms
        })
    });
    let mut out = Vec::with_capacity(SAMPLES);
    group.bench_function("update_slice/cusum", |b| {
        b.iter(|| {
            out.clear();
            det.update_slice(black_box(&x), &mut out).unwrap();
            out.len()
        })
    });
    group.finish();
}

fn banks(c: &mut Criterion<CpuTime>) {
    let mut traces = Traces::new(1_000_000);
    let mut group = c.benchmark_group("bank_step");
    // Each iteration steps ~2 M fresh channel-samples: fewer samples keep the run short.
    group.sample_size(20);
    for channels in [16usize, 1024, 65_536] {
        let steps = bank_steps(channels);
        group.throughput(Throughput::Elements((steps * channels) as u64));
        let mut out: Vec<ChannelAlarm> = Vec::with_capacity(channels);
        for (name, drift) in CUSUMS {
            let cfg = CusumConfig::new(CUSUM_THRESHOLD, drift).unwrap();
            let mut bank = CusumBank::new(channels, cfg).unwrap();
            group.bench_function(BenchmarkId::new(name, channels), |b| {
                b.iter_batched_ref(
                    || traces.matrix(steps, channels),
                    |m| {
                        for row in m.chunks_exact(channels) {
                            out.clear();
                            bank.step(black_box(row), &mut out).unwrap();
                        }
                        out.len()
                    },
                    BatchSize::LargeInput,
                )
            });
            // The same fresh matrix in one call: the time-blocked kernel.
            let id = BenchmarkId::new(format!("{name}_step_many"), channels);
            let mut bank = Bank::from(bank);
            let input = Input::fresh(steps, channels);
            step_many(&mut group, id, &mut traces, &mut bank, input);
        }
        let mut bank = ShewhartBank::new(channels, shewhart_config(50)).unwrap();
        group.bench_function(BenchmarkId::new("shewhart_w50", channels), |b| {
            b.iter_batched_ref(
                || traces.matrix(steps, channels),
                |m| {
                    for row in m.chunks_exact(channels) {
                        out.clear();
                        bank.step(black_box(row), &mut out).unwrap();
                    }
                    out.len()
                },
                BatchSize::LargeInput,
            )
        });
        // The same fresh matrix in one call.
        let id = BenchmarkId::new("shewhart_w50_step_many", channels);
        let mut bank = Bank::from(bank);
        step_many(
            &mut group,
            id,
            &mut traces,
            &mut bank,
            Input::fresh(steps, channels),
        );
    }
    group.finish();
}

/// The fresh matrices a `step_many` benchmark is fed.
#[derive(Clone, Copy)]
struct Input {
    rows: usize,
    channels: usize,
    size: BatchSize,
}

impl Input {
    /// `rows x channels` matrices too large for the cache, set up in batches.
    fn fresh(rows: usize, channels: usize) -> Self {
        Input {
            rows,
            channels,
            size: BatchSize::LargeInput,
        }
    }
}

/// Times `bank.step_many` on a fresh `input.rows x input.channels` matrix per iteration.
fn step_many(
    group: &mut BenchmarkGroup<'_, CpuTime>,
    id: BenchmarkId,
    traces: &mut Traces,
    bank: &mut Bank,
    input: Input,
) {
    let mut out: Vec<ChannelAlarm> = Vec::with_capacity(input.channels);
    group.bench_function(id, |b| {
        b.iter_batched_ref(
            || traces.matrix(input.rows, input.channels),
            |m| {
                out.clear();
                bank.step_many(black_box(m), &mut out).unwrap();
                out.len()
            },
            input.size,
        )
    });
}

/// The banks at 1 024 channels on a batch of 64 fresh rows (512 KiB, just written, as a gateway
/// hands over the readings it has just received), and the floor of the matrix benchmarks above:
/// only reading a fresh 16 MiB matrix once (an XOR of its bits), at the speed of memory.
fn batches(c: &mut Criterion<CpuTime>) {
    const CHANNELS: usize = 1024;
    const ROWS: usize = 64;
    let mut traces = Traces::new(7_000_000);
    let mut group = c.benchmark_group("bank_batch");
    group.sample_size(30);
    group.throughput(Throughput::Elements((ROWS * CHANNELS) as u64));
    let cfg = CusumConfig::new(CUSUM_THRESHOLD, CUSUM_DRIFT).unwrap();
    let input = Input {
        rows: ROWS,
        channels: CHANNELS,
        size: BatchSize::PerIteration,
    };
    let mut bank = Bank::from(CusumBank::new(CHANNELS, cfg).unwrap());
    let id = BenchmarkId::new("cusum_step_many", CHANNELS);
    step_many(&mut group, id, &mut traces, &mut bank, input);
    let mut bank = Bank::from(ShewhartBank::new(CHANNELS, shewhart_config(50)).unwrap());
    let id = BenchmarkId::new("shewhart_w50_step_many", CHANNELS);
    step_many(&mut group, id, &mut traces, &mut bank, input);
    let steps = bank_steps(CHANNELS);
    group.throughput(Throughput::Elements((steps * CHANNELS) as u64));
    group.bench_function(BenchmarkId::new("read_matrix_only", CHANNELS), |b| {
        b.iter_batched_ref(
            || traces.matrix(steps, CHANNELS),
            |m| black_box(&*m).iter().fold(0u64, |a, x| a ^ x.to_bits()),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = config();
    targets = single_channel, banks, batches, replayed
}
criterion_main!(benches);
