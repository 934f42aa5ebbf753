//! The focused beam of the linear array: the lateral pulse-echo profile and
//! the elevation slice at each depth, computed once from the aperture.
//!
//! Lateral: the continuous-wave field of each element is that of a line
//! source in the image plane, `e^{−i k r} / √r` (the 2-D Green's function
//! far from the source), times the element directivity
//! `sinc(π w sin θ / λ)` (Selfridge, Kino & Khuri-Yakub 1980, Appl. Phys.
//! Lett. 37). The transmit field `H_t(x, z, f)` sums the transmit aperture
//! with the delays of the transmit focus; the receive field `H_r` sums the
//! dynamically focused, Tukey-apodized receive aperture of width `z / F#`
//! (the same element sums with the delays of a focus at `z`; Szabo 2014,
//! ch. 7). The two-way field is `H_t H_r` (reciprocity). Over the broadband
//! pulse the lateral profile is the square root of the echo energy at each
//! lateral offset, `A(x) = √(Σ_f S_z(f)² |H_t H_r|²)` (Parseval: the energy
//! of the RF echo received from a point at `x`), signed as the
//! centre-frequency field relative to the axis, so that the main lobe, the
//! side lobes and the edge-wave pedestal of a defocused rectangular
//! transmit aperture, the focal gain and the spectral down-shift
//! (`S_z`, [`crate::pulse`]) all follow from the geometry.
//!
//! Elevation: the same construction across the slice for the elevation
//! lens (fixed focus, transmit and receive), at the spectrum's centroid:
//! the two-way weight `w(y, z) = H_el(y, z)²`. Point targets on the image
//! plane get `|w(0, z)|`; a tissue that does not change across the slice
//! gets `√(∫ |w|² dy)` (the sum of circular Gaussian scatterers across the
//! slice is again circular Gaussian with that variance), which is the
//! partial-volume average of the thick slice.

use crate::beam_config::BeamConfig;
use crate::pulse::{Spectrum, FREQUENCIES};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Depth step of the computed profiles (m); rows interpolate linearly.
pub(crate) const KNOT_STEP: f64 = 0.25e-3;
/// Shallowest depth at which the fields are evaluated (m).
const Z_MIN: f64 = 0.5e-3;
/// Largest lateral extent of the lateral kernel (m).
pub(crate) const MAX_HALF_WIDTH: f64 = 5e-3;

#[inline]
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-9 {
        1.0
    } else {
        x.sin() / x
    }
}

/// One aperture: element positions (m), apodization and focusing path
/// corrections (m).
struct Aperture {
    x: Vec<f64>,
    weight: Vec<f64>,
    delay: Vec<f64>,
}

impl Aperture {
    fn transmit(b: &BeamConfig) -> Self {
        let n = b.transmit_elements;
        let x: Vec<f64> = (0..n)
            .map(|i| (i as f64 - 0.5 * (n - 1) as f64) * b.pitch)
            .collect();
        let f = b.transmit_focus;
        let delay = x.iter().map(|&xi| (xi * xi + f * f).sqrt() - f).collect();
        Aperture {
            weight: vec![1.0; n],
            delay,
            x,
        }
    }

    /// Dynamic receive aperture focused at `z`: `z / F#` wide (at least two
    /// pitches, at most the array), with a Tukey window of 50 % taper.
    fn receive(b: &BeamConfig, z: f64) -> Self {
        let array = b.elements as f64 * b.pitch;
        let width = (z / b.receive_f_number).clamp(2.0 * b.pitch, array);
        let n = b.elements;
        let mut ap = Aperture {
            x: Vec::new(),
            weight: Vec::new(),
            delay: Vec::new(),
        };
        let half = 0.5 * (width + b.pitch); // support: no zero-weight end elements
        for i in 0..n {
            let xi = (i as f64 - 0.5 * (n - 1) as f64) * b.pitch;
            if xi.abs() <= 0.5 * width {
                // Tukey(0.5): flat over the inner half, cosine tapers outside.
                let u = (xi.abs() / half - 0.5).max(0.0) / 0.5;
                ap.weight.push(0.5 * (1.0 + (PI * u).cos()));
                ap.delay.push((xi * xi + z * z).sqrt() - z);
                ap.x.push(xi);
            }
        }
        ap
    }

    /// Adds the field at `(x, z)` for every sampled frequency into `h`.
    fn field(&self, x: f64, z: f64, f: &[f64], c: f64, elem_w: f64, h: &mut [[f64; 2]]) {
        h.fill([0.0, 0.0]);
        let df = f[1] - f[0];
        let lambda0 = c / f[f.len() / 2];
        for ((&xn, &wn), &dn) in self.x.iter().zip(&self.weight).zip(&self.delay) {
            let r = (x - xn).hypot(z);
            let dir = sinc(PI * elem_w * ((x - xn) / r) / lambda0);
            let amp = wn * dir / r.sqrt();
            let path = r - dn;
            let (s0, c0) = (-2.0 * PI * f[0] * path / c).sin_cos();
            let (s1, c1) = (-2.0 * PI * df * path / c).sin_cos();
            let (mut re, mut im) = (amp * c0, amp * s0);
            for hj in h.iter_mut() {
                hj[0] += re;
                hj[1] += im;
                let t = re * c1 - im * s1;
                im = re * s1 + im * c1;
                re = t;
            }
        }
    }
}

/// The beam's profiles on the depth knots `z_n = n · KNOT_STEP`.
#[derive(Debug, Clone)]
pub(crate) struct BeamProfiles {
    /// `lateral[n][k]`: signed amplitude at lateral offset `k · dx` (unnormalized).
    pub lateral: Vec<Vec<f64>>,
    /// Elevation weight of a point on the image plane, per knot (unnormalized).
    pub point: Vec<f64>,
    /// `√(∫ |w|² dy)` per knot (m^½, unnormalized).
    pub diffuse: Vec<f64>,
}

impl BeamProfiles {
    /// Profiles down to `depth` (m) at lateral offsets `k · dx`, `k = 0..=half`.
    pub fn new(b: &BeamConfig, sp: &Spectrum, c: f64, depth: f64, dx: f64, half: usize) -> Self {
        let knots = (depth / KNOT_STEP).ceil() as usize + 2;
        let tx = Aperture::transmit(b);
        let per_knot: Vec<(Vec<f64>, f64, f64)> = (0..knots)
            .into_par_iter()
            .map(|n| {
                let z = (n as f64 * KNOT_STEP).max(Z_MIN);
                let mut s = [0.0; FREQUENCIES];
                sp.at(z, &mut s);
                // The spectrum's shape only: the attenuation's loss of
                // amplitude is the TGC stage's.
                let norm = s.iter().map(|v| v * v).sum::<f64>().sqrt();
                s.iter_mut().for_each(|v| *v /= norm);
                let rx = Aperture::receive(b, z);
                let mut ht = [[0.0; 2]; FREQUENCIES];
                let mut hr = [[0.0; 2]; FREQUENCIES];
                // Centre-frequency sample nearest the centroid, for the sign.
                let fc = sp.centroid(z);
                let jc =
                    sp.f.iter()
                        .enumerate()
                        .min_by(|a, b| (a.1 - fc).abs().total_cmp(&(b.1 - fc).abs()))
                        .map_or(0, |(j, _)| j);
                let mut axis = [1.0, 0.0];
                let mut lat = Vec::with_capacity(half + 1);
                for k in 0..=half {
                    let x = k as f64 * dx;
                    tx.field(x, z, &sp.f, c, b.element_width, &mut ht);
                    rx.field(x, z, &sp.f, c, b.element_width, &mut hr);
                    let mut e = 0.0;
                    let mut hc = [0.0; 2];
                    for j in 0..FREQUENCIES {
                        let h = [
                            ht[j][0] * hr[j][0] - ht[j][1] * hr[j][1],
                            ht[j][0] * hr[j][1] + ht[j][1] * hr[j][0],
                        ];
                        e += s[j] * s[j] * (h[0] * h[0] + h[1] * h[1]);
                        if j == jc {
                            hc = h;
                        }
                    }
                    if k == 0 {
                        axis = hc;
                    }
                    let sign = if hc[0] * axis[0] + hc[1] * axis[1] >= 0.0 {
                        1.0
                    } else {
                        -1.0
                    };
                    lat.push(sign * e.sqrt());
                }
                let (point, diffuse) = elevation(b, z, fc, c);
                (lat, point, diffuse)
            })
            .collect();
        let mut out = BeamProfiles {
            lateral: Vec::with_capacity(knots),
            point: Vec::with_capacity(knots),
            diffuse: Vec::with_capacity(knots),
        };
        for (l, p, d) in per_knot {
            out.lateral.push(l);
            out.point.push(p);
            out.diffuse.push(d);
        }
        out
    }

    /// Linear interpolation of a per-knot quantity at depth `z` (m).
    pub fn interp(v: &[f64], z: f64) -> f64 {
        let s = (z / KNOT_STEP).clamp(0.0, (v.len() - 1) as f64);
        let i = (s.floor() as usize).min(v.len() - 2);
        let t = s - i as f64;
        v[i] * (1.0 - t) + v[i + 1] * t
    }
}

/// Elevation weights at depth `z` and frequency `f`: `(|w(0, z)|, √∫|w|² dy)`
/// for a lens of the configured height and focus (continuous aperture in
/// 40 strips, `y` sampled every 25 µm over ±8 mm).
fn elevation(b: &BeamConfig, z: f64, f: f64, c: f64) -> (f64, f64) {
    const STRIPS: usize = 40;
    let k = 2.0 * PI * f / c;
    let h = b.elevation_height;
    let field = |y: f64| {
        let mut acc = [0.0, 0.0];
        for s in 0..STRIPS {
            let ys = (s as f64 + 0.5) / STRIPS as f64 * h - 0.5 * h;
            let r = (y - ys).hypot(z);
            let d = (ys * ys + b.elevation_focus * b.elevation_focus).sqrt() - b.elevation_focus;
            let (sn, cs) = (-k * (r - d)).sin_cos();
            let a = 1.0 / (r.sqrt() * STRIPS as f64);
            acc[0] += a * cs;
            acc[1] += a * sn;
        }
        acc[0] * acc[0] + acc[1] * acc[1] // |H_el|² = |w| (two-way)
    };
    let dy = 25e-6;
    let mut e = 0.0;
    let n = (8e-3 / dy) as i64;
    for i in -n..=n {
        let w = field(i as f64 * dy);
        e += w * w * dy;
    }
    (field(0.0), e.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_elevation_slice_is_thinnest_near_the_lens_focus() {
        // The diffuse/point ratio is the slice's effective thickness
        // (√∫w² / w(0) in m^½): its minimum lies near the geometric focus,
        // slightly shallower (the focal shift of a weakly focused aperture,
        // Kino 1987, "Acoustic Waves", §3.5): within 25 % of the focus.
        let b = BeamConfig::default();
        let zs: Vec<f64> = (4..=60).map(|i| i as f64 * 1e-3).collect();
        let ratio: Vec<f64> = zs
            .iter()
            .map(|&z| {
                let (p, d) = elevation(&b, z, 7.5e6, 1540.0);
                d / p
            })
            .collect();
        let i = (0..ratio.len())
            .min_by(|&a, &c| ratio[a].total_cmp(&ratio[c]))
            .unwrap();
        assert!(
            (zs[i] / b.elevation_focus - 1.0).abs() < 0.25,
            "thinnest at {} m",
            zs[i]
        );
    }
}
