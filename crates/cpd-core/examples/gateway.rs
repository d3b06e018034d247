//! An edge gateway in Rust: pressure readings as CSV lines on stdin, one detector bank for all
//! meters, alarms as JSON lines on stdout, the bank's snapshot written when the input ends.
//!
//! ```sh
//! cargo run --release --example gateway -p cpd-core -- --kind cusum --threshold 0.3 \
//!     --drift 0.01 --snapshot state.cbor < readings.csv > alarms.jsonl
//! # later, carry on exactly where it stopped:
//! cargo run --release --example gateway -p cpd-core -- --restore state.cbor \
//!     --snapshot state.cbor < more.csv >> alarms.jsonl
//! ```
//!
//! Input: one line per time step, `time,reading_0,...,reading_{n-1}` (heads in metres); an
//! optional header line (a first field that is not a number) is skipped; the channel count is
//! the first data line's (or the restored bank's). A bad line (a wrong number of fields, a
//! value that is not a finite number) is reported on stderr as a JSON line `{"line", "error"}`
//! and skipped: the bank is unchanged. Output: one JSON line per alarm, `{"time", "step",
//! "channel", "direction", "start", "amplitude"}`. Options: `--kind cusum|shewhart`,
//! `--threshold`, `--drift` (CUSUM), `--window`, `--sigma` (Shewhart; `sigma` defaults to the
//! threshold), `--restore FILE`, `--snapshot FILE`. The snapshot is the bytes the Python
//! package's `DetectorBank.restore` reads (`cpd_core::snapshot`: checksummed, so a file altered
//! on disk is refused by name). Rows are stepped in batches of whatever input is
//! already buffered, so a live stream is answered line by line and a file at full speed.

use std::fmt::Write as _;
use std::io::{self, BufRead, BufReader, Read, Write};
use std::path::PathBuf;

use cpd_core::{snapshot, Bank, ChannelAlarm, CusumBank, CusumConfig, Direction, Error};
use cpd_core::{ShewhartBank, ShewhartConfig};

/// Command-line options.
#[derive(Debug, Default, Clone)]
struct Options {
    kind: String,
    threshold: Option<f64>,
    drift: f64,
    window: Option<usize>,
    sigma: Option<f64>,
    restore: Option<PathBuf>,
    snapshot: Option<PathBuf>,
}

fn parse_args(args: impl IntoIterator<Item = String>) -> Result<Options, String> {
    let mut o = Options {
        kind: "cusum".into(),
        ..Options::default()
    };
    let mut args = args.into_iter();
    while let Some(flag) = args.next() {
        let mut value = || args.next().ok_or(format!("{flag} needs a value"));
        let number = |v: String| v.parse::<f64>().map_err(|e| format!("{flag} {v}: {e}"));
        match flag.as_str() {
            "--kind" => o.kind = value()?,
            "--threshold" => o.threshold = Some(number(value()?)?),
            "--drift" => o.drift = number(value()?)?,
            "--sigma" => o.sigma = Some(number(value()?)?),
            "--window" => {
                let v = value()?;
                o.window = Some(v.parse().map_err(|e| format!("--window {v}: {e}"))?);
            }
            "--restore" => o.restore = Some(value()?.into()),
            "--snapshot" => o.snapshot = Some(value()?.into()),
            other => return Err(format!("unknown option {other}")),
        }
    }
    Ok(o)
}

/// A fresh bank of `channels` detectors as the options describe.
fn new_bank(o: &Options, channels: usize) -> Result<Bank, String> {
    let threshold = o.threshold.ok_or("--threshold is required")?;
    let bank: Result<Bank, Error> = match o.kind.as_str() {
        "cusum" => CusumConfig::new(threshold, o.drift)
            .and_then(|c| CusumBank::new(channels, c))
            .map(Bank::from),
        "shewhart" => {
            let window = o.window.ok_or("--window is required for a shewhart bank")?;
            match o.sigma {
                Some(sigma) => ShewhartConfig::new(window, sigma, threshold),
                None => ShewhartConfig::with_threshold(window, threshold),
            }
            .and_then(|c| ShewhartBank::new(channels, c))
            .map(Bank::from)
        }
        other => return Err(format!("--kind must be cusum or shewhart, got {other}")),
    };
    bank.map_err(|e| e.to_string())
}

/// A JSON number, or `null` for a non-finite value.
fn json_number(out: &mut String, v: f64) {
    if v.is_finite() {
        let _ = write!(out, "{v}");
    } else {
        out.push_str("null");
    }
}

/// What a run did.
#[derive(Debug, Default, PartialEq)]
struct Stats {
    rows: u64,
    readings: u64,
    alarms: u64,
    bad_lines: u64,
}

/// The gateway loop: the state carried across batches.
struct Gateway {
    options: Options,
    bank: Option<Bank>,
    /// Row-major readings and times of the rows not yet stepped.
    rows: Vec<f64>,
    times: Vec<f64>,
    alarms: Vec<ChannelAlarm>,
    text: String,
    stats: Stats,
}

/// Rows stepped at most per batch.
const BATCH: usize = 4096;

impl Gateway {
    fn new(options: Options, bank: Option<Bank>) -> Self {
        Gateway {
            options,
            bank,
            rows: Vec::new(),
            times: Vec::with_capacity(BATCH),
            alarms: Vec::new(),
            text: String::new(),
            stats: Stats::default(),
        }
    }

    /// Parses one CSV line into the batch; `Err` describes a bad line (nothing is kept).
    fn push_line(&mut self, line: &str, first: bool) -> Result<(), String> {
        let line = line.trim();
        if line.is_empty() {
            return Ok(());
        }
        let mut fields = line.split(',');
        let time = fields.next().unwrap_or("").trim();
        let Ok(time) = time.parse::<f64>() else {
            return if first {
                Ok(()) // a header
            } else {
                Err(format!("time {time:?} is not a number"))
            };
        };
        let start = self.rows.len();
        for field in fields {
            match field.trim().parse::<f64>() {
                Ok(v) if v.is_finite() => self.rows.push(v),
                _ => {
                    self.rows.truncate(start);
                    return Err(format!("reading {field:?} is not a finite number"));
                }
            }
        }
        let n = self.rows.len() - start;
        let channels = match &self.bank {
            Some(bank) => bank.channels(),
            None => {
                let bank = new_bank(&self.options, n.max(1))?;
                self.bank = Some(bank);
                n
            }
        };
        if n != channels {
            self.rows.truncate(start);
            return Err(format!("{n} readings, expected {channels}"));
        }
        self.times.push(time);
        Ok(())
    }

    /// Steps the buffered rows and writes their alarms.
    fn flush(&mut self, out: &mut impl Write) -> io::Result<()> {
        let Some(bank) = self.bank.as_mut() else {
            return Ok(());
        };
        if self.times.is_empty() {
            return Ok(());
        }
        let first_step = bank.steps_seen();
        self.alarms.clear();
        // Every row was validated while parsing: the bank cannot refuse them.
        bank.step_many(&self.rows, &mut self.alarms)
            .expect("rows are validated when parsed");
        self.stats.rows += self.times.len() as u64;
        self.stats.readings += self.rows.len() as u64;
        self.stats.alarms += self.alarms.len() as u64;
        self.text.clear();
        for a in &self.alarms {
            let time = self.times[(a.alarm.index - first_step) as usize];
            let direction = match a.alarm.direction {
                Direction::Rise => "rise",
                Direction::Drop => "drop",
            };
            self.text.push_str("{\"time\":");
            json_number(&mut self.text, time);
            let _ = write!(
                self.text,
                ",\"step\":{},\"channel\":{},\"direction\":\"{direction}\",\"start\":{},\"amplitude\":",
                a.alarm.index, a.channel, a.alarm.start
            );
            json_number(&mut self.text, a.alarm.amplitude);
            self.text.push_str("}\n");
        }
        out.write_all(self.text.as_bytes())?;
        self.rows.clear();
        self.times.clear();
        Ok(())
    }
}

/// Runs the gateway on `input` until it ends; returns the bank (if any line was seen or one
/// was restored) and the counts.
fn run(
    options: Options,
    bank: Option<Bank>,
    input: impl Read,
    out: &mut impl Write,
    err: &mut impl Write,
) -> io::Result<(Option<Bank>, Stats)> {
    let mut reader = BufReader::with_capacity(1 << 16, input);
    let mut g = Gateway::new(options, bank);
    let mut line = String::new();
    let mut number = 0u64;
    loop {
        line.clear();
        if reader.read_line(&mut line)? == 0 {
            break;
        }
        number += 1;
        if let Err(e) = g.push_line(&line, number == 1) {
            g.stats.bad_lines += 1;
            writeln!(err, "{{\"line\":{number},\"error\":{e:?}}}")?;
        }
        // Step when the batch is full or no more input is waiting (a live stream).
        if g.times.len() >= BATCH || reader.buffer().is_empty() {
            g.flush(out)?;
            out.flush()?;
        }
    }
    g.flush(out)?;
    out.flush()?;
    Ok((g.bank, g.stats))
}

/// The whole program on the given streams: options, `--restore`, the run, `--snapshot`
/// (written to a temporary file beside it, then renamed: a failed write keeps the previous
/// snapshot) and the closing summary on `err`. Returns the exit code: 0, 1 (a file that cannot
/// be read or written, a snapshot that cannot be restored) or 2 (bad options).
fn cli(
    args: impl IntoIterator<Item = String>,
    input: impl Read,
    out: &mut impl Write,
    err: &mut impl Write,
) -> i32 {
    let options = match parse_args(args) {
        Ok(o) => o,
        Err(e) => {
            let _ = writeln!(err, "gateway: {e}");
            return 2;
        }
    };
    let bank = match &options.restore {
        None => None,
        Some(path) => {
            let restored = std::fs::read(path)
                .map_err(|e| format!("cannot read {}: {e}", path.display()))
                .and_then(|bytes| {
                    snapshot::from_bytes::<Bank>(&bytes)
                        .map_err(|e| format!("{}: {e}", path.display()))
                });
            match restored {
                Ok(bank) => Some(bank),
                Err(e) => {
                    let _ = writeln!(err, "gateway: {e}");
                    return 1;
                }
            }
        }
    };
    let start = std::time::Instant::now();
    let (bank, stats) = match run(options.clone(), bank, input, out, err) {
        Ok(done) => done,
        Err(e) => {
            let _ = writeln!(err, "gateway: {e}");
            return 1;
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    if let (Some(path), Some(bank)) = (&options.snapshot, &bank) {
        let tmp = path.with_extension("tmp");
        let written = std::fs::write(&tmp, snapshot::to_bytes(bank))
            .and_then(|()| std::fs::rename(&tmp, path));
        if let Err(e) = written {
            let _ = std::fs::remove_file(&tmp);
            let _ = writeln!(err, "gateway: cannot write {}: {e}", path.display());
            return 1;
        }
    }
    let _ = writeln!(
        err,
        "gateway: {} rows, {} readings, {} alarms, {} bad lines in {seconds:.3} s ({:.2} M readings/s)",
        stats.rows,
        stats.readings,
        stats.alarms,
        stats.bad_lines,
        stats.readings as f64 / seconds / 1e6
    );
    0
}

fn main() {
    let (stdin, stdout, stderr) = (io::stdin(), io::stdout(), io::stderr());
    let mut out = io::BufWriter::with_capacity(1 << 16, stdout.lock());
    let code = cli(
        std::env::args().skip(1),
        stdin.lock(),
        &mut out,
        &mut stderr.lock(),
    );
    drop(out);
    std::process::exit(code);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(args: &[&str]) -> Options {
        parse_args(args.iter().map(|s| s.to_string())).unwrap()
    }

    /// A CSV of `steps` rows of 3 meters; meter 1 drops by 1.5 m at step `burst`.
    fn csv(from: usize, steps: usize, burst: usize) -> String {
        let mut s = String::from("time,m0,m1,m2\n");
        for t in from..from + steps {
            let noise = |c: usize| ((t * 7919 + c * 104_729) % 101) as f64 * 1e-4;
            let drop = if t >= burst { 1.5 } else { 0.0 };
            let _ = writeln!(
                s,
                "{},{},{},{}",
                t as f64 * 0.1,
                200.0 + noise(0),
                185.0 - drop + noise(1),
                170.0 + noise(2)
            );
        }
        s
    }

    fn gateway(o: &Options, bank: Option<Bank>, input: &str) -> (Option<Bank>, Stats, String) {
        let (mut out, mut err) = (Vec::new(), Vec::new());
        let (bank, stats) = run(o.clone(), bank, input.as_bytes(), &mut out, &mut err).unwrap();
        (bank, stats, String::from_utf8(out).unwrap())
    }

    #[test]
    fn csv_in_alarms_out_and_a_snapshot_that_carries_on() {
        for args in [
            &["--threshold", "0.5", "--drift", "0.01"][..],
            &["--kind", "shewhart", "--window", "20", "--threshold", "0.5"][..],
        ] {
            let o = options(args);
            let whole = csv(0, 200, 120);
            let (bank, stats, alarms) = gateway(&o, None, &whole);
            assert_eq!((stats.rows, stats.readings, stats.bad_lines), (200, 600, 0));
            let first = alarms.lines().next().expect("the burst alarms");
            assert!(
                first.contains("\"channel\":1,\"direction\":\"drop\""),
                "{first}"
            );
            assert!(first.starts_with("{\"time\":12,\"step\":120,"), "{first}");
            // Stop at step 90, snapshot, restore, carry on: the same alarms in all.
            let (head, tail) = (csv(0, 90, 120), csv(90, 110, 120));
            let (stopped, _, a1) = gateway(&o, None, &head);
            let bytes = snapshot::to_bytes(&stopped.unwrap());
            let restored: Bank = snapshot::from_bytes(&bytes).unwrap();
            let (resumed, _, a2) = gateway(&o, Some(restored), tail.split_once('\n').unwrap().1);
            assert_eq!(a1 + &a2, alarms);
            assert_eq!(
                snapshot::to_bytes(&resumed.unwrap()),
                snapshot::to_bytes(&bank.unwrap())
            );
        }
    }

    #[test]
    fn bad_lines_are_reported_and_skipped() {
        let o = options(&["--threshold", "0.5"]);
        let good = csv(0, 50, 30);
        let mut lines: Vec<&str> = good.lines().collect();
        lines.insert(10, "0.95,200.0,nan,170.0");
        lines.insert(20, "1.9,200.0,185.0");
        lines.insert(30, "x,200.0,185.0,170.0");
        let bad = lines.join("\n");
        let (mut out, mut err) = (Vec::new(), Vec::new());
        let (bank, stats) = run(o.clone(), None, bad.as_bytes(), &mut out, &mut err).unwrap();
        assert_eq!((stats.rows, stats.bad_lines), (50, 3));
        let err = String::from_utf8(err).unwrap();
        assert_eq!(err.lines().count(), 3);
        assert!(
            err.lines().next().unwrap().starts_with("{\"line\":11,"),
            "{err}"
        );
        // Exactly as if the bad lines had never been sent.
        let (clean, _, alarms) = gateway(&o, None, &good);
        assert_eq!(String::from_utf8(out).unwrap(), alarms);
        assert_eq!(
            snapshot::to_bytes(&bank.unwrap()),
            snapshot::to_bytes(&clean.unwrap())
        );
    }

    /// The program with its files: a snapshot written at the end of one run, restored by the
    /// next; the two runs give the alarms of one; unreadable or foreign files are refused.
    #[test]
    fn the_program_snapshots_to_a_file_and_carries_on_from_it() {
        let dir = std::env::temp_dir().join(format!("gateway-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let state = dir.join("state.cbor");
        let args = |extra: &[&str]| -> Vec<String> {
            ["--threshold", "0.5", "--drift", "0.01"]
                .iter()
                .chain(extra)
                .map(|s| s.to_string())
                .collect()
        };
        let program = |args: Vec<String>, input: &str| {
            let (mut out, mut err) = (Vec::new(), Vec::new());
            let code = cli(args, input.as_bytes(), &mut out, &mut err);
            let text = |v: Vec<u8>| String::from_utf8(v).unwrap();
            (code, text(out), text(err))
        };
        let (code, whole, err) = program(args(&[]), &csv(0, 200, 120));
        assert_eq!(code, 0, "{err}");
        assert!(err.contains("200 rows, 600 readings"), "{err}");
        let path = state.to_str().unwrap();
        let (code, first, err) = program(args(&["--snapshot", path]), &csv(0, 90, 120));
        assert_eq!(code, 0, "{err}");
        assert!(state.exists() && !state.with_extension("tmp").exists());
        let tail = csv(90, 110, 120);
        let restore = args(&["--restore", path, "--snapshot", path]);
        let (code, second, err) = program(restore.clone(), &tail);
        assert_eq!(code, 0, "{err}");
        assert_eq!(first + &second, whole);
        // A missing or corrupt snapshot is refused by name, and the file is left as it was.
        let missing = dir.join("missing.cbor");
        let (code, out, err) = program(args(&["--restore", missing.to_str().unwrap()]), &tail);
        assert_eq!((code, out.as_str()), (1, ""));
        assert!(
            err.contains("cannot read") && err.contains("missing.cbor"),
            "{err}"
        );
        let mut altered = std::fs::read(&state).unwrap();
        let mid = altered.len() / 2;
        altered[mid] ^= 0x20;
        std::fs::write(&state, &altered).unwrap();
        let (code, out, err) = program(restore.clone(), &tail);
        assert_eq!((code, out.as_str()), (1, ""));
        assert!(err.contains("checksum mismatch"), "{err}");
        std::fs::write(&state, b"not a snapshot").unwrap();
        let (code, _, err) = program(restore, &tail);
        assert_eq!(code, 1);
        assert!(err.starts_with(&format!("gateway: {path}: ")), "{err}");
        assert_eq!(std::fs::read(&state).unwrap(), b"not a snapshot");
        // A snapshot that cannot be written: exit 1, named.
        let nowhere = dir.join("no-such-dir").join("state.cbor");
        let (code, _, err) = program(args(&["--snapshot", nowhere.to_str().unwrap()]), &tail);
        assert_eq!(code, 1);
        assert!(
            err.contains("cannot write") && err.contains("no-such-dir"),
            "{err}"
        );
        let (code, _, err) = program(vec!["--bogus".to_string()], "");
        assert_eq!(code, 2);
        assert!(err.contains("unknown option --bogus"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn options_are_validated() {
        assert!(parse_args(["--bogus".to_string()]).is_err());
        assert!(parse_args(["--threshold".to_string()]).is_err());
        let o = options(&["--threshold", "-1"]);
        assert!(new_bank(&o, 3).unwrap_err().contains("threshold"));
        let o = options(&["--kind", "shewhart", "--threshold", "0.5"]);
        assert!(new_bank(&o, 3).unwrap_err().contains("window"));
    }
}
