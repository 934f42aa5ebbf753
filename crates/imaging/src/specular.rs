//! Specular interfaces of the soft tissue (issue 21): fascia, vessel walls
//! and the artery's intima–media double line, drawn as smooth lines whose
//! echo follows the angle between the interface and the beam.
//!
//! A smooth interface much wider than the beam reflects coherently: its
//! echo is a line of constant phase along the interface, not speckle. Each
//! interface is sampled by one reflector per scatterer bin (image column),
//! at the depth where the interface crosses the column, in tissue
//! coordinates (m), so that the deformation carries it with the tissue.
//! Each frame, the interface's slope in the image, `dz/du` by central
//! differences between neighbouring columns (after the skin displacement,
//! the column compression and the vessels' warps), sets its gain by the
//! cortex's law ([`crate::scatterers::specular_gain`]): a smooth interface
//! tilted by `θ` sends its echo `2θ` off the beam's axis, and the receive
//! aperture collects it only for `2θ ≲ 16°` (Szabo 2014, ch. 3), so the
//! amplitude is `exp(−θ²/(2θ₀²))`, `θ₀` = [`SPECULAR_LOBE`]. The floor of
//! the cortex's law (its diffuse backscatter) is here the interface's own
//! tissue speckle, which stays in the scatterer field.
//!
//! The reflector's phase is set each frame to cancel the carrier phase the
//! splat gives its depth (`e^{−i 2k₀ z}`), so the samples of one interface
//! add in phase under the lateral PSF whatever the column pitch: the angle
//! dependence is the law above, not an artefact of the sampling (a tilted
//! line sampled every `Δx` would otherwise alias back in phase at
//! `tan θ = λ/(2Δx)`).
//!
//! Levels (peak echo of a line facing the beam, dB re the mean speckle
//! intensity of the muscle class at the same depth, before attenuation;
//! the perimysium lines raise muscle's mean echo by ≈ 2 dB over its
//! class), listed on [`Interface`]: a specular echo scales as the
//! interface's amplitude reflection coefficient `R`, and the model's scale
//! is set by the femoral cortex, `R` = 0.64 at +35 dB ([`Tissue::Cortex`]),
//! so a line of reflection `R` lies at `35 + 20 log₁₀(R/0.64)` dB. Published
//! densities and speeds of sound (fat, muscle, tendon and ligament as dense
//! collagen; `src/published_acoustics.rs`, which tests the levels) give
//! `R` = 0.060 (fat on muscle) to 0.214 (fat on collagen): +14.4 to +25.5
//! dB. The +35 dB anchor itself is an estimate (no published backscatter
//! coefficient of thigh muscle at 7.5 MHz was found to set it absolutely).
//! The
//! amplitude of a reflector follows from the PSF tables: a line of
//! reflectors of amplitude `A` one per column peaks at
//! `A w_e Σ_k h_lat(k)` (`w_e` the elevation weight, the axial kernel's
//! peak is 1), muscle speckle has the mean intensity `ρ w_e² Δx Σ_k h_lat(k)²
//! E_ax` ([`PsfTables::speckle_unit`]), hence
//! `A = √(10^{G/10} ρ Δx Σ h² E_ax) / Σ h`.

use crate::anatomy::{Anatomy, LumenLaw};
use crate::config::ImagingConfig;
use crate::psf::{PsfTables, PHASE_STEPS};
use crate::stages::{image_depth, FrameGeometry};
use crate::tissue::Tissue;
use crate::warp::WarpSet;

pub(crate) use crate::scatterers::SPECULAR_LOBE;

/// Intima–media thickness of the femoral artery (m): 0.55 mm, the mean of
/// the reference values of healthy adults aged 20–60 (women 543 ± 63 µm,
/// men 562 ± 74 µm, 98 subjects without cardiovascular risk factors;
/// "Reference values of intima-medial thickness of carotid and femoral
/// arteries in subjects aged 20 to 60 years and without cardiovascular
/// risk factors", Arch. Mal. Coeur Vaiss. 2000, 93(6):721–6, PMID
/// 10916655; consistent with 0.47–0.51 mm in 160 adults aged 18–50, Wang
/// et al., "A cross-sectional analysis of femoral artery intima-media
/// thickness", SVS Vascular Annual Meeting 2012, PS170). The media between
/// the two lines is hypoechoic.
pub const INTIMA_MEDIA: f64 = 0.55e-3;

/// Diffuse echo of the arterial media relative to muscle (dB): the
/// hypoechoic band between the intima–media double line (smooth muscle; an
/// estimate: the double line's pattern, lumen–intima and media–adventitia
/// echoes around a dark media, is Pignoli et al. 1986, "Intimal plus medial
/// thickness of the arterial wall: a direct measurement with ultrasound
/// imaging", Circulation 74(6):1399, but no level of the media was found).
const MEDIA_DB: f64 = -15.0;

/// No neighbour (an interface's first or last column).
const NONE: u32 = u32::MAX;

/// A kind of specular interface and its level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Interface {
    /// Deep fascia, intermuscular fascia, a muscle's outline: +20 dB, the
    /// brightest soft-tissue lines of the thigh (a sheet of dense collagen
    /// between fat or muscle on each side): `R` ≈ 0.10, within the
    /// published 0.060–0.214 (+14.4 to +25.5 dB; module docs).
    Fascia,
    /// Lumen–wall interface of a vein: +20 dB (the thin bright wall of a
    /// patent vein, as bright as a fascia where it faces the beam: the
    /// collagen-rich adventitia on perivascular fat, `R` ≈ 0.10, within the
    /// published range of the module docs).
    VeinWall,
    /// Lumen–intima interface of an artery: +14 dB (the inner, thinner
    /// line of the double line: blood to intima). An estimate: no published
    /// impedance of the intima was found; set 6 dB under the adventitia's
    /// line, the weaker of the double line (Pignoli et al. 1986).
    Intima,
    /// Media–adventitia interface of an artery: +20 dB (the outer line of
    /// the double line, the brighter one: media to collagen-rich
    /// adventitia, within the published range of the module docs).
    Adventitia,
}

impl Interface {
    /// Peak echo of the line facing the beam (dB re muscle speckle).
    pub fn level_db(self) -> f64 {
        match self {
            Interface::Fascia => 20.0,
            Interface::VeinWall => 20.0,
            Interface::Intima => 14.0,
            Interface::Adventitia => 20.0,
        }
    }
}

/// Factor on the diffuse (speckle) amplitude of a tissue scatterer at
/// `(u, d)` (m, tissue coordinates) of class `tissue` in vessel `vessel`,
/// for the tissues whose echo the specular lines now carry: a fascia's
/// speckle falls to muscle's (the sheet shows as its line, not as a band
/// of brighter speckle), an artery's media (within [`INTIMA_MEDIA`] of the
/// lumen) to [`MEDIA_DB`].
pub(crate) fn diffuse_factor(
    anatomy: &Anatomy,
    tissue: Tissue,
    vessel: Option<usize>,
    u: f64,
    d: f64,
) -> f64 {
    let db = |t: Tissue| anatomy.echo_of(t, vessel).unwrap_or(0.0);
    match (tissue, vessel) {
        (Tissue::Fascia, _) => 10f64.powf((db(Tissue::Muscle) - db(Tissue::Fascia)) / 20.0),
        (Tissue::ArteryWall, Some(i)) => {
            let v = &anatomy.vessels()[i].vessel;
            if v.contains(u, d, INTIMA_MEDIA.min(v.wall)) {
                10f64.powf((MEDIA_DB - db(Tissue::ArteryWall)) / 20.0)
            } else {
                1.0
            }
        }
        _ => 1.0,
    }
}

/// The specular reflectors of the section, binned like the scatterer field
/// ([`crate::scatterers::ScattererField::bins`]), with their per-frame
/// amplitudes.
#[derive(Debug, Clone)]
pub(crate) struct SpecularField {
    /// `bin_start[b]..bin_start[b + 1]`: reflectors of bin `b`.
    pub bin_start: Vec<u32>,
    /// Depth below the undeformed skin (m), increasing within a bin.
    pub depth: Vec<f32>,
    /// Amplitude facing the beam (envelope units).
    base: Vec<f32>,
    /// The same interface's reflector in the previous / next bin, or [`NONE`].
    prev: Vec<u32>,
    next: Vec<u32>,
    /// This frame's complex amplitude (gain and phase applied).
    pub amp: Vec<[f32; 2]>,
    /// This frame's image depth (m) of each reflector of the window.
    z: Vec<f64>,
}

/// One crossing of an interface with a column: depth (m), kind, and the
/// interface's identity (to link neighbouring columns).
type Crossing = (f64, Interface, u32);

/// The interfaces of `anatomy` crossing the column `u` (m, tissue
/// coordinates) into `out`: the fascia lines where the tissue is fascia,
/// each vessel's lumen–wall interfaces (an artery's also at
/// [`INTIMA_MEDIA`] into its wall) where the wall is that vessel's.
fn crossings(anatomy: &Anatomy, u: f64, out: &mut Vec<Crossing>) {
    out.clear();
    let c = anatomy.config();
    let is_fascia = |d: f64| anatomy.classify(u, d).0 == Tissue::Fascia;
    let deep = c.skin_thickness + c.fat_thickness + 0.5 * c.fascia_thickness;
    if is_fascia(deep) {
        out.push((deep, Interface::Fascia, 0));
    }
    let inter = anatomy.intermuscular_fascia(u);
    if is_fascia(inter) {
        out.push((inter, Interface::Fascia, 1));
    }
    for (j, v) in anatomy.muscle_outlines().enumerate() {
        let (cm, h) = v.chord(u, 0.0);
        if h > 0.0 {
            for (s, side) in [(-1.0, 0), (1.0, 1)] {
                let d = cm + s * h;
                if is_fascia(d) {
                    out.push((d, Interface::Fascia, 2 + 2 * j as u32 + side));
                }
            }
        }
    }
    let eps = 1e-6;
    for (i, sv) in anatomy.vessels().iter().enumerate() {
        let v = &sv.vessel;
        let wall = sv.tissues.1;
        let (cl, h) = v.chord(u, 0.0);
        let key = 100 + 4 * i as u32;
        let artery = matches!(sv.law, LumenLaw::Artery);
        let inner = if artery {
            Interface::Intima
        } else {
            Interface::VeinWall
        };
        if h > 0.0 {
            for (s, side) in [(-1.0, 0), (1.0, 1)] {
                let d = cl + s * h;
                if anatomy.classify(u, d + s * eps) == (wall, Some(i)) {
                    out.push((d, inner, key + side));
                }
            }
        }
        if artery && INTIMA_MEDIA < v.wall {
            let (co, ho) = v.chord(u, INTIMA_MEDIA);
            if ho > 0.0 {
                for (s, side) in [(-1.0, 0), (1.0, 1)] {
                    let d = co + s * ho;
                    if anatomy.classify(u, d) == (wall, Some(i)) {
                        out.push((d, Interface::Adventitia, key + 2 + side));
                    }
                }
            }
        }
    }
    out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
}

/// Amplitude of a reflector line of `level_db` (dB re muscle speckle) at
/// image row `row` (see the module docs).
fn line_amplitude(cfg: &ImagingConfig, t: &PsfTables, row: usize, level_db: f64) -> f64 {
    let h = t.lat_half as i64;
    let (sum, sum2) = (-h..=h).fold((0.0, 0.0), |(s, s2), k| {
        let w = t.lateral_at(k, row) as f64;
        (s + w, s2 + w * w)
    });
    let ax = t.axial.energy[t.axial.knot(row as f64)];
    (10f64.powf(level_db / 10.0) * cfg.scatterer_density * cfg.pixel_width() * sum2 * ax).sqrt()
        / sum.max(1e-12)
}

impl SpecularField {
    /// The reflectors of `anatomy` in the `bins` columns centred at
    /// `u_first + b Δx` (m, the anatomy's frame) for the image of `cfg`.
    pub fn new(
        cfg: &ImagingConfig,
        t: &PsfTables,
        anatomy: &Anatomy,
        bins: usize,
        u_first: f64,
    ) -> Self {
        let dx = cfg.pixel_width();
        let dz = cfg.pixel_depth();
        let mut bin_start = Vec::with_capacity(bins + 1);
        let (mut depth, mut base, mut keys) = (Vec::new(), Vec::new(), Vec::new());
        let mut col = Vec::new();
        for b in 0..bins {
            bin_start.push(depth.len() as u32);
            crossings(anatomy, u_first + b as f64 * dx, &mut col);
            for &(d, kind, key) in &col {
                let row = ((d / dz) as usize).min(cfg.rows - 1);
                depth.push(d as f32);
                base.push(line_amplitude(cfg, t, row, kind.level_db()) as f32);
                keys.push(key);
            }
        }
        bin_start.push(depth.len() as u32);
        let n = depth.len();
        let (mut prev, mut next) = (vec![NONE; n], vec![NONE; n]);
        for b in 1..bins {
            let (p0, p1) = (bin_start[b - 1] as usize, bin_start[b] as usize);
            let q1 = bin_start[b + 1] as usize;
            for q in p1..q1 {
                if let Some(p) = (p0..p1).find(|&p| keys[p] == keys[q]) {
                    prev[q] = p as u32;
                    next[p] = q as u32;
                }
            }
        }
        SpecularField {
            bin_start,
            depth,
            base,
            prev,
            next,
            amp: vec![[0.0, 0.0]; n],
            z: vec![0.0; n],
        }
    }

    /// No reflectors in `bins` bins (a phantom).
    pub fn new_empty(bins: usize) -> Self {
        SpecularField {
            bin_start: vec![0; bins + 1],
            depth: Vec::new(),
            base: Vec::new(),
            prev: Vec::new(),
            next: Vec::new(),
            amp: Vec::new(),
            z: Vec::new(),
        }
    }

    /// Reflectors of bin `b`.
    pub fn range(&self, b: usize) -> std::ops::Range<usize> {
        self.bin_start[b] as usize..self.bin_start[b + 1] as usize
    }

    /// This frame's amplitudes of the reflectors of the window bins
    /// `w0 .. w0 + surface.len()` (each with its skin displacement and
    /// warps): image depth, slope to the neighbouring columns (central
    /// differences, one-sided at the window's and the interface's ends, a
    /// lone reflector taken as parallel to the beam), gain, and the phase
    /// that cancels the splat's carrier. Allocates nothing.
    pub fn prepare_frame(
        &mut self,
        t: &PsfTables,
        g: &FrameGeometry,
        dx: f64,
        w0: usize,
        surface: &[f64],
        warps: &[WarpSet],
    ) {
        let nb = surface.len();
        for b in 0..nb {
            for k in self.range(w0 + b) {
                self.z[k] = image_depth(g, surface[b], &warps[b], self.depth[k] as f64);
            }
        }
        let (lo, hi) = (
            self.bin_start[w0] as usize,
            self.bin_start[w0 + nb] as usize,
        );
        let inside = |k: u32| k != NONE && (lo..hi).contains(&(k as usize));
        let phase_mask = PHASE_STEPS as i32 - 1;
        for k in lo..hi {
            let (p, q) = (self.prev[k], self.next[k]);
            let z = self.z[k];
            let slope = match (inside(p), inside(q)) {
                (true, true) => (self.z[q as usize] - self.z[p as usize]) / (2.0 * dx),
                (true, false) => (z - self.z[p as usize]) / dx,
                (false, true) => (self.z[q as usize] - z) / dx,
                (false, false) => f64::INFINITY,
            };
            let theta = slope.abs().atan();
            let gain = (-0.5 * (theta / SPECULAR_LOBE).powi(2)).exp();
            let a = self.base[k] * gain as f32;
            // The splat's phase index of this depth (the same operations).
            let ph = (z * t.phase_per_metre) as i32 & phase_mask;
            let c = t.phase[ph as usize];
            self.amp[k] = [a * c[0], -a * c[1]];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anatomy_config::{AnatomyConfig, VeinState};

    #[test]
    fn every_vessel_wall_and_fascia_has_lines() {
        let a = Anatomy::new(&AnatomyConfig::default(), VeinState::Healthy).unwrap();
        let mut out = Vec::new();
        // Through the artery's centre: deep and intermuscular fascia, the
        // artery's two lines on each wall.
        crossings(&a, a.artery().lateral, &mut out);
        let kinds: Vec<Interface> = out.iter().map(|c| c.1).collect();
        assert_eq!(
            kinds,
            [
                Interface::Fascia,
                Interface::Fascia,
                Interface::Adventitia,
                Interface::Intima,
                Interface::Intima,
                Interface::Adventitia
            ]
        );
        let v = a.artery();
        let far = out[5].0 - out[4].0;
        assert!((far - INTIMA_MEDIA).abs() < 1e-9, "{far}");
        assert!((out[4].0 - (v.depth + v.radius_b)).abs() < 1e-9);
        crossings(&a, a.vein().lateral, &mut out);
        assert_eq!(out.iter().filter(|c| c.1 == Interface::VeinWall).count(), 2);
    }
}
