//! The time loop: [`Model::run`] and the boundaries it solves each step.

use crate::model::{Element, ElementKind, Model, Output, Pipe};
use crate::{pow2, Error, G, ROOT_TOLERANCE};

/// Each point's pipe constants, for the interior points' loop over whole arrays.
struct PointConstants {
    ga: Vec<f64>,
    gadt: Vec<f64>,
    theta: Vec<f64>,
    cf: Vec<f64>,
    ga2: Vec<f64>,
}

impl PointConstants {
    fn new(pipes: &[Pipe], points: usize) -> Self {
        // points no pipe holds get harmless constants (their results are never read)
        let mut c = Self {
            ga: vec![1.0; points],
            gadt: vec![0.0; points],
            theta: vec![0.0; points],
            cf: vec![0.0; points],
            ga2: vec![2.0; points],
        };
        for p in pipes {
            for i in p.offset..=p.offset + p.n {
                c.ga[i] = p.ga;
                c.gadt[i] = p.gadt;
                c.theta[i] = p.theta;
                c.cf[i] = p.cf;
                c.ga2[i] = p.ga + p.ga;
            }
        }
        c
    }
}

/// `s V + g/a H - s J + g/a dt V theta` (TSNet's `cal_Cs`, steady friction `J`).
#[inline(always)]
fn characteristic(sign: f64, v: f64, h: f64, p: &Pipe) -> f64 {
    let j = p.cf * v * v.abs();
    sign * v + p.ga * h - sign * j + p.gadt * v * p.theta
}

/// NumPy's `maximum`: NaN if either is.
#[inline]
fn maximum(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if a >= b {
        a
    } else {
        b
    }
}

impl Model {
    /// Runs the transient: the heads of the recorded points at every step.
    ///
    /// # Errors
    /// [`Error`] if the model does not [`validate`](Model::validate).
    pub fn run(&self) -> Result<Output, Error> {
        self.validate()?;
        let steps = self.steps;
        let mut out = Output {
            heads: Vec::with_capacity(steps * self.record.len()),
            junction_failed: vec![0; self.junctions.len()],
            dead_failed: vec![0; self.dead_ends.len()],
            element_warnings: vec![[0; 3]; self.elements.len()],
        };
        let mut h = self.h0.clone();
        let mut v = self.v0.clone();
        let mut hn = self.h0.clone();
        let mut vn = self.v0.clone();
        out.heads.extend(self.record.iter().map(|&r| h[r]));
        let mut emitter = self.emitter.clone();
        let mut demand = self.demand.clone();
        let base: Vec<f64> = self.pulses.iter().map(|&i| self.demand[i]).collect();
        let mut k = vec![0.0; emitter.len()];
        let mut products = vec![0.0; self.contributions.len()];
        let constants = PointConstants::new(&self.pipes, self.h0.len());
        for ts in 1..steps {
            let nb = self.bursts.len();
            for (b, &i) in self.bursts.iter().enumerate() {
                emitter[i] = self.burst_series[ts * nb + b];
            }
            let np_ = self.pulses.len();
            for (q, &i) in self.pulses.iter().enumerate() {
                demand[i] = base[q] * (1.0 + self.pulse_series[ts * np_ + q]);
            }
            for ((k, e), d) in k.iter_mut().zip(&emitter).zip(&demand) {
                *k = e + d;
            }
            self.interior(&constants, &h, &v, &mut hn, &mut vn);
            self.junction_ends(&h, &v, &k, &mut products, &mut hn, &mut vn, &mut out);
            self.dead(&h, &v, &k, &mut hn, &mut vn, &mut out.dead_failed);
            for r in &self.reservoirs {
                let p = &self.pipes[r.end.pipe];
                let (v1, h1) = (v[r.end.near], h[r.end.near]);
                let j = p.cf * v1 * v1.abs();
                hn[r.end.out] = r.head;
                vn[r.end.out] = v1 + r.side * (p.ga * (r.head - h1)) - j;
            }
            let nv = self.valve_ends.len();
            for (i, e) in self.valve_ends.iter().enumerate() {
                let p = &self.pipes[e.end.pipe];
                let (v1, h1) = (v[e.end.near], h[e.end.near]);
                let vb = self.valve_series[ts * nv + i];
                let j = p.cf * vb * vb.abs();
                hn[e.end.out] = h1 + e.side * (p.ag * (vb - v1)) + e.side * (p.ag * j);
                vn[e.end.out] = vb;
            }
            let ne = self.elements.len();
            for (i, e) in self.elements.iter().enumerate() {
                let at = (ts * ne + i) * 3;
                let param = [
                    self.element_series[at],
                    self.element_series[at + 1],
                    self.element_series[at + 2],
                ];
                let (head, velocity) = self.element(e, param, &h, &v, &mut out.element_warnings[i]);
                hn[e.out] = head;
                vn[e.out] = velocity;
            }
            out.heads.extend(self.record.iter().map(|&r| hn[r]));
            core::mem::swap(&mut h, &mut hn);
            core::mem::swap(&mut v, &mut vn);
        }
        Ok(out)
    }

    /// Interior points (TSNet's `inner_node_steady`), computed at every point but the first
    /// and last over whole arrays (so that the compiler vectorizes it); a pipe's ends are
    /// computed from garbage here and overwritten by their boundaries afterwards.
    fn interior(&self, c: &PointConstants, h: &[f64], v: &[f64], hn: &mut [f64], vn: &mut [f64]) {
        let n = h.len();
        if n < 3 {
            return;
        }
        let (hl, hr) = (&h[..n - 2], &h[2..]);
        let (vl, vr) = (&v[..n - 2], &v[2..]);
        let (ga, gadt) = (&c.ga[1..n - 1], &c.gadt[1..n - 1]);
        let (theta, cf, ga2) = (&c.theta[1..n - 1], &c.cf[1..n - 1], &c.ga2[1..n - 1]);
        let (hn, vn) = (&mut hn[1..n - 1], &mut vn[1..n - 1]);
        for i in 0..n - 2 {
            let (v0, h0, v1, h1) = (vl[i], hl[i], vr[i], hr[i]);
            let c0 = v0 + ga[i] * h0 - cf[i] * v0 * v0.abs() + gadt[i] * v0 * theta[i];
            // `characteristic(-1.0, ..)`: -1 * x is -x and y - (-j) is y + j, exactly
            let c1 = -v1 + ga[i] * h1 + cf[i] * v1 * v1.abs() + gadt[i] * v1 * theta[i];
            let hp = (c0 + c1) / ga2[i];
            hn[i] = hp;
            vn[i] = -c1 + ga[i] * hp;
        }
    }

    /// Junction ends (TSNet's `add_leakage`: demand and emitter `Q = k sqrt(p)`).
    #[allow(clippy::too_many_arguments)]
    fn junction_ends(
        &self,
        h: &[f64],
        v: &[f64],
        k: &[f64],
        products: &mut [f64],
        hn: &mut [f64],
        vn: &mut [f64],
        out: &mut Output,
    ) {
        for (c, product) in self.contributions.iter().zip(products.iter_mut()) {
            let p = &self.pipes[c.pipe];
            *product = characteristic(c.sign, v[c.index], h[c.index], p) * p.area;
        }
        for (e, j) in self.junctions.iter().enumerate() {
            // the four lanes in registers (an array indexed by lane went through memory)
            let (mut a0, mut a1, mut a2, mut a3) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for (c, product) in self.contributions[j.contributions.clone()]
                .iter()
                .zip(&products[j.contributions.clone()])
            {
                match c.lane {
                    0 => a0 += product,
                    1 => a1 += product,
                    2 => a2 += product,
                    _ => a3 += product,
                }
            }
            let nb = (a0 + a1) + (a2 + a3);
            let p = &self.pipes[j.end.pipe];
            let co = characteristic(j.sign, v[j.end.near], h[j.end.near], p);
            let a = nb + co * p.area;
            let kj = k[j.node];
            let k2 = pow2(kj);
            let b1 = -2.0 * a * j.b - k2;
            let c1 = pow2(a) + k2 * self.elevation[j.node];
            let jb2 = j.b2;
            let delta = pow2(b1) - 4.0 * jb2 * c1;
            if delta <= -ROOT_TOLERANCE {
                out.junction_failed[e] += 1;
            }
            let hp = if delta >= 0.0 {
                (-b1 - delta.sqrt()) / (2.0 * jb2)
            } else {
                (-b1) / (2.0 * jb2)
            };
            hn[j.end.out] = hp;
            vn[j.end.out] = if j.sign < 0.0 {
                -co + p.ga * hp
            } else {
                co - p.ga * hp
            };
        }
    }

    /// Dead ends (TSNet's `dead_end`, with burstloc's closed end below atmospheric pressure).
    fn dead(
        &self,
        h: &[f64],
        v: &[f64],
        k: &[f64],
        hn: &mut [f64],
        vn: &mut [f64],
        failed: &mut [u64],
    ) {
        for (i, d) in self.dead_ends.iter().enumerate() {
            let p = &self.pipes[d.end.pipe];
            let (v1, h1) = (v[d.end.near], h[d.end.near]);
            let (kn, elev) = (k[d.node], self.elevation[d.node]);
            let j = p.cf * v1 * v1.abs();
            let (bq, cq) = if d.at_start {
                (
                    -p.ag * kn / p.area_dead,
                    p.ag * v1 - p.ag * j - h1 - p.gadt * v1 * p.theta + elev,
                )
            } else {
                (
                    p.ag * kn / p.area_dead,
                    -p.ag * v1 + p.ag * j - h1 - p.gadt * v1 * p.theta + elev,
                )
            };
            let delta = pow2(bq) - 4.0 * cq;
            let ok = delta >= 0.0;
            let closed = kn == 0.0 && cq > 0.0 && d.floor < elev;
            let root = (if ok { delta } else { 0.0 }).sqrt();
            if delta <= -ROOT_TOLERANCE && !closed {
                failed[i] += 1;
            }
            let x = if !ok {
                (-bq) / 2.0
            } else if d.at_start {
                (-bq - root) / 2.0
            } else {
                (-bq + root) / 2.0
            };
            let hp = if closed {
                maximum(elev - cq, d.floor)
            } else {
                pow2(x) + elev
            };
            let friction = p.cf2 * v1 * v1.abs();
            let vp = if d.at_start {
                v1 - p.ga * h1 - friction + p.ga * hp - p.gadt * v1 * p.theta
            } else {
                v1 + p.ga * h1 - friction - p.ga * hp + p.gadt * v1 * p.theta
            };
            hn[d.end.out] = hp;
            vn[d.end.out] = vp;
        }
    }

    /// A pump or valve end (TSNet's `valve_node`, `pump_node`, `source_pump`).
    fn element(
        &self,
        e: &Element,
        param: [f64; 3],
        h: &[f64],
        v: &[f64],
        warn: &mut [u64; 3],
    ) -> (f64, f64) {
        let (i1, p1, s1) = e.link1;
        let (i2, p2, s2) = e.link2;
        let (pipe1, pipe2) = (&self.pipes[p1], &self.pipes[p2]);
        let (a1, a2) = (pipe1.area, pipe2.area);
        let c10 = characteristic(s1, v[i1], h[i1], pipe1);
        let c11 = pipe1.ga;
        let c20 = characteristic(s2, v[i2], h[i2], pipe2);
        let c21 = pipe2.ga;
        let root = |bq: f64, delta: f64, plus: bool, warn: &mut [u64; 3]| -> f64 {
            if delta >= 0.0 {
                if plus {
                    (-bq + delta.sqrt()) / 2.0
                } else {
                    (-bq - delta.sqrt()) / 2.0
                }
            } else {
                if delta <= -ROOT_TOLERANCE || delta.is_nan() {
                    warn[0] += 1;
                }
                (-bq) / 2.0
            }
        };
        match e.kind {
            ElementKind::Valve => {
                let kl = param[0];
                let gk = 2.0 * G * kl;
                let bq = gk * (a2 / a1 / c11 + 1.0 / c21);
                let cq = gk * (c20 / c21 - c10 / c11);
                let vp = root(bq, pow2(bq) - 4.0 * cq, true, warn);
                if vp >= 0.0 {
                    if e.at_start {
                        ((c20 + vp) / c21, vp)
                    } else {
                        let vp = vp * a2 / a1;
                        ((c10 - vp) / c11, vp)
                    }
                } else {
                    let bq = gk * (-a1 / a2 / c21 - 1.0 / c11);
                    let cq = gk * (-c20 / c21 + c10 / c11);
                    let vp = root(bq, pow2(bq) - 4.0 * cq, false, warn);
                    if e.at_start {
                        let vp = vp * a1 / a2;
                        ((c20 + vp) / c21, vp)
                    } else {
                        ((c10 - vp) / c11, vp)
                    }
                }
            }
            ElementKind::Pump { suction } => {
                let ap = param[0] * pow2(a1);
                let bp = param[1] * a1;
                let cp = param[2];
                let bq = 1.0 / ap * (bp - 1.0 / c11 - a1 / c21 / a2);
                let cq = 1.0 / ap * (-c20 / c21 + c10 / c11 + cp);
                let vp = root(bq, pow2(bq) - 4.0 * cq, true, warn);
                let hp = ap * pow2(vp) + bp * vp + cp;
                if vp > 0.0 && hp >= 0.0 {
                    if e.at_start {
                        let vp = vp * a1 / a2;
                        ((c20 + vp) / c21, vp)
                    } else {
                        ((c10 - vp) / c11, vp)
                    }
                } else if vp < 0.0 {
                    warn[1] += 1;
                    if e.at_start {
                        ((c20 + 0.0) / c21, 0.0)
                    } else {
                        ((c10 - 0.0) / c11, 0.0)
                    }
                } else {
                    warn[2] += 1;
                    let head = match (suction, e.at_start) {
                        (true, true) => (c20 + vp) / c21,
                        (true, false) => (c10 - vp) / c11,
                        (false, true) => (c10 - vp) / c11 + 0.0,
                        (false, false) => (c20 + vp) / c21 + 0.0,
                    };
                    (head, vp)
                }
            }
            ElementKind::Source { sump } => {
                let ap = param[0] * pow2(a2);
                let bp = param[1] * a2;
                let cp = param[2];
                let aq = ap * pow2(c21);
                let bq = bp * c21 - 2.0 * ap * c20 * c21 - 1.0;
                let cq = ap * pow2(c20) - bp * c20 + sump + cp;
                let delta = pow2(bq) - 4.0 * aq * cq;
                let hp = if delta >= 0.0 {
                    (-bq - delta.sqrt()) / (2.0 * aq)
                } else {
                    if delta <= -ROOT_TOLERANCE || delta.is_nan() {
                        warn[0] += 1;
                    }
                    (-bq) / (2.0 * aq)
                };
                // TSNet's `if HP > Hsump: ... else: HP = Hsump` (NaN too)
                let hp = if hp > sump { hp } else { sump };
                let vp = -c20 + c21 * hp;
                if vp <= 0.0 {
                    warn[1] += 1;
                    ((c20 + 0.0) / c21, 0.0)
                } else {
                    (hp, vp)
                }
            }
        }
    }
}
