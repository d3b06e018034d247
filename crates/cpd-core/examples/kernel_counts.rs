//! Instructions per sample of every detector kernel, counted by Callgrind: a figure that the
//! machine's load cannot change (timings on a shared machine can), to compare two builds of a
//! kernel on exactly the same work.
//!
//! ```sh
//! # Every kernel under Callgrind (valgrind must be on PATH), a table of instructions/sample:
//! RUSTFLAGS="-C target-cpu=x86-64-v3" cargo run --release --example kernel_counts -p cpd-core -- all
//! # One kernel, natively (or under any profiler):
//! cargo run --release --example kernel_counts -p cpd-core -- cusum_bank_1024
//! # One kernel under Callgrind by hand: the count is the `totals:` of the output file,
//! # divided by the `samples=` the program prints.
//! valgrind --tool=callgrind --collect-atstart=no '--toggle-collect=*kernel_counts*measure*' \
//!     --callgrind-out-file=cg.out target/release/examples/kernel_counts shewhart_update_10
//! ```
//!
//! `x86-64-v3` (AVX2, FMA unused: Rust never fuses) because Valgrind decodes no AVX-512: a
//! `target-cpu=native` build on an AVX-512 machine stops with an illegal instruction under it.
//!
//! Each kernel runs on fresh seeded noisy heads, generated as the criterion benchmarks
//! generate them (`benches/common/traces.rs`): the detector is first warmed up on data it
//! then never sees again (a trace, or one row that primes a bank), and only the calls on
//! fresh data are counted (`measure`). Single detectors see 4 traces of 100 000 samples;
//! banks one `T x channels` matrix of about 2 M readings (`T` as in the benchmarks), in one
//! call (`step_many`) or, for the `*_bank_step_*` kernels, one call per row (`step`).

use std::hint::black_box;
use std::process::{Command, ExitCode};

use cpd_core::{Alarm, Bank, ChannelAlarm, Cusum, CusumBank, CusumConfig, Shewhart, ShewhartBank};

#[path = "../benches/common/traces.rs"]
mod traces;
use traces::*;

/// Fresh single-channel traces counted per kernel.
const TRACES: usize = 4;

/// The kernels, by name: `(name, what it runs)`.
fn kernels() -> Vec<(String, Kernel)> {
    let mut k = vec![
        ("cusum_update".to_string(), Kernel::CusumUpdate),
        ("cusum_update_slice".to_string(), Kernel::CusumSlice),
    ];
    for w in WINDOWS {
        k.push((format!("shewhart_update_{w}"), Kernel::ShewhartUpdate(w)));
    }
    for w in WINDOWS {
        k.push((
            format!("shewhart_update_slice_{w}"),
            Kernel::ShewhartSlice(w),
        ));
    }
    for c in [16, 1024, 65_536] {
        k.push((format!("cusum_bank_{c}"), Kernel::CusumBank(c)));
    }
    k.push((
        "cusum_bank_step_1024".to_string(),
        Kernel::CusumBankStep(1024),
    ));
    k.push((
        "shewhart_bank_w50_1024".to_string(),
        Kernel::ShewhartBank(50, 1024),
    ));
    k.push(("cusum_bank_step_16".to_string(), Kernel::CusumBankStep(16)));
    for c in [16, 1024] {
        k.push((
            format!("shewhart_bank_step_w50_{c}"),
            Kernel::ShewhartBankStep(50, c),
        ));
    }
    k
}

/// One kernel: what is counted.
#[derive(Clone, Copy)]
enum Kernel {
    /// `Cusum::update` per sample, drift 0.01.
    CusumUpdate,
    /// `Cusum::update_slice`, drift 0.01.
    CusumSlice,
    /// `Shewhart::update` per sample, window `W`.
    ShewhartUpdate(usize),
    /// `Shewhart::update_slice`, window `W`.
    ShewhartSlice(usize),
    /// `CusumBank::step_many` over `channels`, drift 0.01.
    CusumBank(usize),
    /// `CusumBank::step` row by row over `channels`, drift 0.01.
    CusumBankStep(usize),
    /// `ShewhartBank::step_many`, window `W`, over `channels`.
    ShewhartBank(usize, usize),
    /// `ShewhartBank::step` row by row, window `W`, over `channels`.
    ShewhartBankStep(usize, usize),
}

/// The counted region: Callgrind collects only inside this function (`--toggle-collect`).
#[inline(never)]
fn measure(work: &mut dyn FnMut() -> usize) -> usize {
    work()
}

/// A single-channel detector, fed per sample or per slice.
trait Stream {
    /// `update`: whether `x` raised an alarm.
    fn one(&mut self, x: f64) -> bool;
    /// `update_slice`.
    fn many(&mut self, xs: &[f64], out: &mut Vec<Alarm>);
}

impl Stream for Cusum {
    fn one(&mut self, x: f64) -> bool {
        self.update(x).unwrap().is_some()
    }
    fn many(&mut self, xs: &[f64], out: &mut Vec<Alarm>) {
        self.update_slice(xs, out).unwrap()
    }
}

impl Stream for Shewhart {
    fn one(&mut self, x: f64) -> bool {
        self.update(x).unwrap().is_some()
    }
    fn many(&mut self, xs: &[f64], out: &mut Vec<Alarm>) {
        self.update_slice(xs, out).unwrap()
    }
}

/// Warms `det` up on one trace, then counts it on [`TRACES`] fresh ones, per slice (`slice`)
/// or per sample; returns the number of samples counted.
fn single(mut det: impl Stream, slice: bool, traces: &mut Traces) -> usize {
    let mut out = Vec::with_capacity(SAMPLES);
    det.many(&traces.heads(SAMPLES), &mut out);
    let mut alarms = 0;
    for _ in 0..TRACES {
        let x = traces.heads(SAMPLES);
        alarms += measure(&mut || {
            out.clear();
            if slice {
                det.many(black_box(&x), &mut out);
                return out.len();
            }
            x.iter().filter(|&&v| det.one(black_box(v))).count()
        });
    }
    black_box(alarms);
    TRACES * SAMPLES
}

/// Warms `bank` up on `warm` rows (one primes a CUSUM bank, `W` fill a Shewhart window),
/// then counts one call of `step_many` on a fresh matrix (or a `step` per row: `by_row`);
/// returns the readings counted.
fn bank(mut bank: Bank, warm: usize, by_row: bool, traces: &mut Traces) -> usize {
    let channels = bank.channels();
    let mut out: Vec<ChannelAlarm> = Vec::new();
    bank.step_many(&traces.matrix(warm, channels), &mut out)
        .unwrap();
    let steps = bank_steps(channels);
    let m = traces.matrix(steps, channels);
    let alarms = measure(&mut || {
        out.clear();
        if by_row {
            for row in m.chunks_exact(channels) {
                bank.step(black_box(row), &mut out).unwrap();
            }
        } else {
            bank.step_many(black_box(&m), &mut out).unwrap();
        }
        out.len()
    });
    black_box(alarms);
    steps * channels
}

/// Runs `kernel` on fresh data; returns the number of samples (channel-samples) counted.
fn run(kernel: Kernel) -> usize {
    let mut traces = Traces::new(42);
    match kernel {
        Kernel::CusumUpdate => single(cusum(CUSUM_DRIFT), false, &mut traces),
        Kernel::CusumSlice => single(cusum(CUSUM_DRIFT), true, &mut traces),
        Kernel::ShewhartUpdate(w) | Kernel::ShewhartSlice(w) => {
            let det = Shewhart::new(shewhart_config(w)).unwrap();
            single(det, matches!(kernel, Kernel::ShewhartSlice(_)), &mut traces)
        }
        Kernel::CusumBank(channels) | Kernel::CusumBankStep(channels) => {
            let cfg = CusumConfig::new(CUSUM_THRESHOLD, CUSUM_DRIFT).unwrap();
            let b = CusumBank::new(channels, cfg).unwrap();
            let by_row = matches!(kernel, Kernel::CusumBankStep(_));
            bank(b.into(), 1, by_row, &mut traces)
        }
        Kernel::ShewhartBank(w, channels) | Kernel::ShewhartBankStep(w, channels) => {
            let b = ShewhartBank::new(channels, shewhart_config(w)).unwrap();
            let by_row = matches!(kernel, Kernel::ShewhartBankStep(..));
            bank(b.into(), w, by_row, &mut traces)
        }
    }
}
/// Runs `name` under Callgrind; returns instructions per sample.
fn count(exe: &str, name: &str) -> Result<f64, String> {
    let file = std::env::temp_dir().join(format!("kernel_counts.{}.{name}", std::process::id()));
    let out = Command::new("valgrind")
        .args([
            "--tool=callgrind",
            "--collect-atstart=no",
            "--toggle-collect=*kernel_counts*measure*",
        ])
        .arg(format!("--callgrind-out-file={}", file.display()))
        .args([exe, name])
        .output()
        .map_err(|e| format!("cannot run valgrind: {e}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let samples: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("samples="))
        .and_then(|v| v.trim().parse().ok())
        .ok_or_else(|| format!("{name}: {}", String::from_utf8_lossy(&out.stderr)))?;
    let report = std::fs::read_to_string(&file).map_err(|e| format!("{name}: {e}"))?;
    // Best effort: a leftover file in the temporary directory is harmless.
    let _ = std::fs::remove_file(&file);
    let total: f64 = report
        .lines()
        .find_map(|l| l.strip_prefix("totals:"))
        .and_then(|v| v.trim().parse().ok())
        .ok_or_else(|| format!("{name}: no totals in the Callgrind output"))?;
    Ok(total / samples)
}

fn main() -> ExitCode {
    let arg = std::env::args().nth(1).unwrap_or_default();
    let kernels = kernels();
    if arg == "all" {
        let exe = std::env::args().next().unwrap_or_default();
        println!("| kernel | instructions/sample |\n|---|---|");
        for (name, _) in &kernels {
            match count(&exe, name) {
                Ok(v) => println!("| {name} | {v:.2} |"),
                Err(e) => {
                    eprintln!("{e}");
                    return ExitCode::FAILURE;
                }
            }
        }
        return ExitCode::SUCCESS;
    }
    match kernels.iter().find(|(n, _)| *n == arg) {
        Some(&(_, k)) => {
            println!("samples={}", run(k));
            ExitCode::SUCCESS
        }
        None => {
            let names: Vec<&str> = kernels.iter().map(|(n, _)| n.as_str()).collect();
            eprintln!("usage: kernel_counts all|{}", names.join("|"));
            ExitCode::FAILURE
        }
    }
}
