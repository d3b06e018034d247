//! Per-sample cost of the streaming detectors and banks.
//!
//! `cargo bench -p cpd-core -- --measurement-time 2 --warm-up-time 1`
//!
//! Time is the benchmark thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`), not wall time: the
//! 2-core machines are shared, and other processes would otherwise inflate the figures.
//! Set `CPD_BENCH_WALL=1` to measure wall time instead.
//!
//! Inputs are seeded pressure-like heads: 200 m with 1 mm noise and a rare burst step, so the
//! detectors alarm occasionally as they would in service.

use std::hint::black_box;

use cpd_core::{
    ChannelAlarm, Cusum, CusumBank, CusumConfig, Shewhart, ShewhartBank, ShewhartConfig,
};
use cpu_time::ThreadTime;
use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

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

/// SplitMix64-driven heads: 200 m, ±0.5 mm uniform noise, a 1.5 m drop every ~20 000 samples.
fn heads(n: usize, seed: u64) -> Vec<f64> {
    let mut state = seed;
    let mut next = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let mut level = 200.0;
    (0..n)
        .map(|_| {
            let r = next();
            if r % 20_000 == 0 {
                level -= 1.5;
            }
            level + 1e-3 * ((r >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        })
        .collect()
}

const SAMPLES: usize = 100_000;

fn single_channel(c: &mut Criterion<CpuTime>) {
    let x = heads(SAMPLES, 1);
    let mut group = c.benchmark_group("update");
    group.throughput(Throughput::Elements(SAMPLES as u64));
    // drift = 0.01, and drift = 0 (burstloc's default: the drift-free fast path).
    for (name, drift) in [("cusum", 0.01), ("cusum_nodrift", 0.0)] {
        group.bench_function(name, |b| {
            let mut det = Cusum::new(CusumConfig::new(0.5, drift).unwrap());
            b.iter(|| {
                let mut alarms = 0u32;
                for &v in &x {
                    alarms += det.update(black_box(v)).unwrap().is_some() as u32;
                }
                alarms
            })
        });
    }
    for w in [10usize, 100, 10_000] {
        group.bench_with_input(BenchmarkId::new("shewhart", w), &w, |b, &w| {
            let mut det = Shewhart::new(ShewhartConfig::new(w, 3.0, 0.5).unwrap()).unwrap();
            b.iter(|| {
                let mut alarms = 0u32;
                for &v in &x {
                    alarms += det.update(black_box(v)).unwrap().is_some() as u32;
                }
                alarms
            })
        });
    }
    group.finish();

    // The batch entry point (what the Python `update_many` calls): state stays in registers.
    let mut group = c.benchmark_group("update_slice");
    group.throughput(Throughput::Elements(SAMPLES as u64));
    let mut out = Vec::with_capacity(SAMPLES);
    for (name, drift) in [("cusum", 0.01), ("cusum_nodrift", 0.0)] {
        group.bench_function(name, |b| {
            let mut det = Cusum::new(CusumConfig::new(0.5, drift).unwrap());
            b.iter(|| {
                out.clear();
                det.update_slice(black_box(&x), &mut out).unwrap();
                out.len()
            })
        });
    }
    for w in [10usize, 100, 10_000] {
        group.bench_with_input(BenchmarkId::new("shewhart", w), &w, |b, &w| {
            let mut det = Shewhart::new(ShewhartConfig::new(w, 3.0, 0.5).unwrap()).unwrap();
            b.iter(|| {
                out.clear();
                det.update_slice(black_box(&x), &mut out).unwrap();
                out.len()
            })
        });
    }
    group.finish();
}

/// `ROWS` distinct rows of `channels` readings, cycled through by the bank benchmarks.
const ROWS: usize = 16;

fn rows(channels: usize) -> Vec<Vec<f64>> {
    let cols: Vec<Vec<f64>> = (0..channels).map(|c| heads(ROWS, 100 + c as u64)).collect();
    (0..ROWS)
        .map(|t| cols.iter().map(|col| col[t]).collect())
        .collect()
}

fn banks(c: &mut Criterion<CpuTime>) {
    let mut group = c.benchmark_group("bank_step");
    for channels in [16usize, 1024, 65_536] {
        let data = rows(channels);
        group.throughput(Throughput::Elements(channels as u64));
        for (name, drift) in [("cusum", 0.01), ("cusum_nodrift", 0.0)] {
            group.bench_with_input(
                BenchmarkId::new(name, channels),
                &channels,
                |b, &channels| {
                    let mut bank =
                        CusumBank::new(channels, CusumConfig::new(0.5, drift).unwrap()).unwrap();
                    let mut out: Vec<ChannelAlarm> = Vec::with_capacity(channels);
                    let mut t = 0;
                    b.iter(|| {
                        out.clear();
                        bank.step(black_box(&data[t % ROWS]), &mut out).unwrap();
                        t += 1;
                        out.len()
                    })
                },
            );
        }
        group.bench_with_input(
            BenchmarkId::new("shewhart_w50", channels),
            &channels,
            |b, &channels| {
                let cfg = ShewhartConfig::new(50, 3.0, 0.5).unwrap();
                let mut bank = ShewhartBank::new(channels, cfg).unwrap();
                let mut out: Vec<ChannelAlarm> = Vec::with_capacity(channels);
                let mut t = 0;
                b.iter(|| {
                    out.clear();
                    bank.step(black_box(&data[t % ROWS]), &mut out).unwrap();
                    t += 1;
                    out.len()
                })
            },
        );
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = config();
    targets = single_channel, banks
}
criterion_main!(benches);
