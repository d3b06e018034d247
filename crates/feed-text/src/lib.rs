//! The text of a readings feed file: CSV lines `timestamp,meter,value`, as
//! `burstloc monitor --readings` reads them, for a table of time steps (one value per meter).
//!
//! Every number is written as Python's `repr` writes it ([`write_float`]): the shortest
//! decimal that reads back to the same double bit for bit (`-0.0` keeps its sign), with an
//! exponent (`1e+16`, `1.5e-05`) where `repr` uses one. [`write_lines`] leaves out the values
//! that are not finite and the ones marked filled (a gateway's hold of a missing reading, not a
//! reading). Nothing here touches Python: the binding (`burstloc._core.feed_text`) reads the
//! steps with the GIL and calls this without it.

#![forbid(unsafe_code)]
#![deny(missing_docs)]

use core::fmt;

/// Why a table of steps cannot be written; the message names the sizes or the row.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// `values` does not hold one value per meter for each timestamp.
    Shape {
        /// Values given.
        values: usize,
        /// Timestamps given.
        rows: usize,
        /// Meters given.
        meters: usize,
    },
    /// `filled` is neither empty nor one flag per value.
    Filled {
        /// Flags given.
        flags: usize,
        /// Values given.
        values: usize,
    },
    /// A timestamp that is not a finite number.
    Timestamp {
        /// Its row.
        row: usize,
        /// Its value.
        value: f64,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::Shape {
                values,
                rows,
                meters,
            } => write!(
                f,
                "{values} values for {rows} steps of {meters} meters (one value per meter per step)"
            ),
            Error::Filled { flags, values } => write!(
                f,
                "{flags} filled flags for {values} values (none, or one per value)"
            ),
            Error::Timestamp { row, value } => {
                write!(
                    f,
                    "step {row} has a timestamp that is not a finite number: {value}"
                )
            }
        }
    }
}

impl std::error::Error for Error {}

/// Appends the lines `timestamp,meter,value\n` of a table of steps: row `i` is
/// `timestamps[i]` with its values `values[i * m .. (i + 1) * m]` for the `m` `meters`, in
/// that order; a value that is not finite, or whose flag in `filled` is set (`filled` empty:
/// none is), is left out. Every number as [`write_float`] writes it. Returns the lines
/// written; nothing is appended on an error.
///
/// # Errors
/// [`Error::Shape`] when `values` is not `timestamps.len() * meters.len()` long,
/// [`Error::Filled`] when `filled` is neither empty nor as long as `values`,
/// [`Error::Timestamp`] for a timestamp that is not finite.
pub fn write_lines<S: AsRef<str>>(
    out: &mut Vec<u8>,
    meters: &[S],
    timestamps: &[f64],
    values: &[f64],
    filled: &[bool],
) -> Result<usize, Error> {
    let m = meters.len();
    if values.len() != timestamps.len() * m {
        return Err(Error::Shape {
            values: values.len(),
            rows: timestamps.len(),
            meters: m,
        });
    }
    if !filled.is_empty() && filled.len() != values.len() {
        return Err(Error::Filled {
            flags: filled.len(),
            values: values.len(),
        });
    }
    if let Some((row, &value)) = timestamps.iter().enumerate().find(|(_, t)| !t.is_finite()) {
        return Err(Error::Timestamp { row, value });
    }
    let names: Vec<Vec<u8>> = meters
        .iter()
        .map(|name| [b",", name.as_ref().as_bytes(), b","].concat())
        .collect();
    out.reserve(values.len() * 32);
    let mut stamp = Vec::with_capacity(32);
    let mut lines = 0;
    for (i, &t) in timestamps.iter().enumerate() {
        stamp.clear();
        write_float(&mut stamp, t);
        for (j, name) in names.iter().enumerate() {
            let k = i * m + j;
            let v = values[k];
            if !v.is_finite() || filled.get(k).copied().unwrap_or(false) {
                continue;
            }
            out.extend_from_slice(&stamp);
            out.extend_from_slice(name);
            write_float(out, v);
            out.push(b'\n');
            lines += 1;
        }
    }
    Ok(lines)
}

/// Appends the text Python's `repr` gives `x`: for a finite `x`, the shortest decimal that
/// reads back to it exactly, positional from `1e-4` up to below `1e16` (`0.0001`, `50.0`,
/// `1000000000000000.0`), with an exponent of at least two digits beyond (`1e-05`,
/// `1.2345e+16`); `nan`, `inf` and `-inf` otherwise.
pub fn write_float(out: &mut Vec<u8>, x: f64) {
    if !x.is_finite() {
        out.extend_from_slice(match x {
            _ if x.is_nan() => b"nan",
            _ if x > 0.0 => b"inf",
            _ => b"-inf",
        });
        return;
    }
    if x.is_sign_negative() {
        out.push(b'-');
    }
    if x == 0.0 {
        out.extend_from_slice(b"0.0");
        return;
    }
    let mut buffer = ryu::Buffer::new();
    let (digits, point) = Decimal::of(buffer.format_finite(x.abs()));
    let digits = &digits.digits[..digits.len];
    let n = digits.len() as i32;
    if !(-4 < point && point <= 16) {
        // d.ddde+XX, as repr writes it (point: the digits are 0.ddd x 10^point)
        out.push(digits[0]);
        if n > 1 {
            out.push(b'.');
            out.extend_from_slice(&digits[1..]);
        }
        let exponent = point - 1;
        out.push(b'e');
        out.push(if exponent < 0 { b'-' } else { b'+' });
        let e = exponent.unsigned_abs();
        if e >= 100 {
            out.push(b'0' + (e / 100) as u8);
        }
        out.push(b'0' + (e / 10 % 10) as u8);
        out.push(b'0' + (e % 10) as u8);
    } else if point <= 0 {
        out.extend_from_slice(b"0.");
        out.resize(out.len() + point.unsigned_abs() as usize, b'0');
        out.extend_from_slice(digits);
    } else if point >= n {
        out.extend_from_slice(digits);
        out.resize(out.len() + (point - n) as usize, b'0');
        out.extend_from_slice(b".0");
    } else {
        let (whole, fraction) = digits.split_at(point as usize);
        out.extend_from_slice(whole);
        out.push(b'.');
        out.extend_from_slice(fraction);
    }
}

/// The significant digits of a positive decimal text, without leading or trailing zeros (17
/// at most for a double's shortest form).
struct Decimal {
    digits: [u8; 24],
    len: usize,
}

impl Decimal {
    /// The digits of `text` (ryu's form of a positive finite double: `123.45`, `1e16`,
    /// `1.5e-7`, `0.001`) and where the point goes: the value is `0.DIGITS x 10^point`.
    fn of(text: &str) -> (Decimal, i32) {
        let (mantissa, exponent) = match text.split_once(['e', 'E']) {
            Some((m, e)) => (m, e.parse::<i32>().unwrap_or(0)),
            None => (text, 0),
        };
        let bytes = mantissa.as_bytes();
        let dot = bytes.iter().position(|&c| c == b'.').unwrap_or(bytes.len());
        let first = bytes.iter().position(|&c| (b'1'..=b'9').contains(&c));
        let Some(first) = first else {
            return (
                Decimal {
                    digits: [b'0'; 24],
                    len: 1,
                },
                1,
            ); // zero (not given here)
        };
        let mut d = Decimal {
            digits: [0; 24],
            len: 0,
        };
        for &c in bytes[first..].iter().filter(|c| c.is_ascii_digit()) {
            if d.len < d.digits.len() {
                d.digits[d.len] = c;
                d.len += 1;
            }
        }
        while d.len > 1 && d.digits[d.len - 1] == b'0' {
            d.len -= 1;
        }
        let point = if first < dot {
            (dot - first) as i32
        } else {
            -((first - dot - 1) as i32)
        };
        (d, point + exponent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(x: f64) -> String {
        let mut out = Vec::new();
        write_float(&mut out, x);
        String::from_utf8(out).unwrap()
    }

    /// Python's repr of each (python3 -c 'print(repr(x))').
    #[test]
    fn numbers_are_written_as_python_repr_writes_them() {
        let cases: [(f64, &str); 27] = [
            (0.0, "0.0"),
            (-0.0, "-0.0"),
            (1.0, "1.0"),
            (50.0, "50.0"),
            (0.1, "0.1"),
            (52.3417, "52.3417"),
            (-12.5, "-12.5"),
            (1e16, "1e+16"),
            (1e15, "1000000000000000.0"),
            (1e-4, "0.0001"),
            (1e-5, "1e-05"),
            (1.5e-5, "1.5e-05"),
            (5e-324, "5e-324"),
            (f64::MAX, "1.7976931348623157e+308"),
            (f64::MIN_POSITIVE, "2.2250738585072014e-308"),
            (9007199254740992.0, "9007199254740992.0"),
            (2f64.powi(60) + 2048.0, "1.152921504606849e+18"),
            (123456789012345.67, "123456789012345.67"),
            (1800000000.004, "1800000000.004"),
            (0.1 + 0.2, "0.30000000000000004"),
            (1e22, "1e+22"),
            (1e100, "1e+100"),
            (-1.2345e-7, "-1.2345e-07"),
            (9999999999999998.0, "9999999999999998.0"),
            (1e-300, "1e-300"),
            (f64::NAN, "nan"),
            (f64::NEG_INFINITY, "-inf"),
        ];
        for (x, want) in cases {
            assert_eq!(text(x), want, "{x:e}");
        }
    }

    /// xorshift64*: seeded bit patterns without a dependency.
    fn bits(seed: u64) -> impl Iterator<Item = u64> {
        let mut s = seed;
        core::iter::from_fn(move || {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            Some(s.wrapping_mul(0x2545_f491_4f6c_dd1d))
        })
    }

    #[test]
    fn every_finite_double_reads_back_bit_for_bit() {
        let random = bits(7).take(200_000).map(f64::from_bits);
        let near_tens = (-323..309).flat_map(|k| {
            let t: f64 = format!("1e{k}").parse().unwrap();
            [
                t,
                f64::from_bits(t.to_bits() + 1),
                f64::from_bits(t.to_bits() - 1),
            ]
        });
        let powers = (-1074..1024).map(|k| 2f64.powi(k));
        for x in random
            .chain(near_tens)
            .chain(powers)
            .filter(|x| x.is_finite())
        {
            for x in [x, -x] {
                let t = text(x);
                assert_eq!(t.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{t}");
            }
        }
    }

    #[test]
    fn readings_as_meters_send_them_keep_their_decimals() {
        for (k, n) in bits(3).take(10_000).enumerate() {
            let cents = (n % 10_000_000) as f64 / 1e4; // four decimals, as `simulate --feed`
            let t = text(cents);
            let shown = format!("{cents:.4}");
            let trimmed = shown.trim_end_matches('0');
            let want = if trimmed.ends_with('.') {
                format!("{trimmed}0")
            } else {
                trimmed.to_owned()
            };
            assert_eq!(t, want, "case {k}");
        }
    }

    #[test]
    fn lines_leave_out_what_is_not_a_reading() {
        let mut out = b"kept".to_vec();
        let values = [50.0, f64::NAN, -0.0, 1e16, f64::INFINITY, 40.25];
        let filled = [false, false, true, false, false, false];
        let n = write_lines(&mut out, &["a", "b", "c"], &[1.5, 1.75], &values, &filled).unwrap();
        let want = "kept1.5,a,50.0\n1.75,a,1e+16\n1.75,c,40.25\n";
        assert_eq!((n, String::from_utf8(out).unwrap()), (3, want.to_owned()));
        let mut out = Vec::new();
        assert_eq!(write_lines(&mut out, &["a"], &[0.25], &[2.0], &[]), Ok(1));
        assert_eq!(out, b"0.25,a,2.0\n");
    }

    #[test]
    fn tables_that_do_not_fit_are_refused_and_nothing_is_written() {
        let mut out = Vec::new();
        let wrong = write_lines(&mut out, &["a", "b"], &[1.0, 2.0], &[1.0, 2.0, 3.0], &[]);
        assert_eq!(
            wrong,
            Err(Error::Shape {
                values: 3,
                rows: 2,
                meters: 2
            })
        );
        let flags = write_lines(&mut out, &["a"], &[1.0], &[1.0], &[true, false]);
        assert_eq!(
            flags,
            Err(Error::Filled {
                flags: 2,
                values: 1
            })
        );
        let stamp = write_lines(&mut out, &["a"], &[1.0, f64::NAN], &[1.0, 2.0], &[]);
        assert!(matches!(stamp, Err(Error::Timestamp { row: 1, .. })));
        assert!(out.is_empty());
        let said = Error::Shape {
            values: 3,
            rows: 2,
            meters: 2,
        }
        .to_string();
        assert_eq!(
            said,
            "3 values for 2 steps of 2 meters (one value per meter per step)"
        );
    }
}
