//! The vessels' lumens in a frame: what the renderer reports (area,
//! pressure, centre, half-axes) and how each lumen is drawn (its height
//! ratio and widening, [`crate::widen`]).

use super::{check_input, FrameInput, Renderer};
use crate::anatomy::Anatomy;
use crate::carry::stacked;
use crate::deformation::column_depth;
use crate::deformation::SectionDeformation;
use crate::error::ImagingError;
use crate::pressure::stress_under_rectangle;
use crate::reverberation::LumenSpan;
use crate::warp::{compensated_ratio, VesselWarp, MAX_VESSELS};
use crate::widen::{blood_fraction, lumen_shape, side_caps, LumenShape};

/// The state of one vessel's lumen in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lumen {
    /// Lumen area (m²).
    pub area: f64,
    /// Lumen area at rest (m²).
    pub rest_area: f64,
    /// Tissue pressure at the vessel (Pa), from the probe pressure.
    pub tissue_pressure: f64,
    /// Lateral position of the centre (m, image frame).
    pub lateral: f64,
    /// Depth of the deformed lumen's centre below the probe face (m).
    pub depth: f64,
    /// Half-height of the deformed lumen (m).
    pub half_height: f64,
    /// Half-width of the lumen (m).
    pub half_width: f64,
}

/// Vein and artery lumens of a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LumenReport {
    /// The femoral vein.
    pub vein: Lumen,
    /// The femoral artery.
    pub artery: Lumen,
}

/// A vessel's lumen in a frame (image frame, m).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct VesselLumen {
    pub(super) lateral: f64,
    pub(super) depth: f64,
    pub(super) half_height: f64,
    pub(super) half_width: f64,
    pub(super) wall: f64,
}

impl VesselLumen {
    /// The lumen's span in the column at lateral `u` (m, image frame), as
    /// an ellipse of the lumen's half-width and half-height.
    pub(super) fn span(&self, u: f64) -> Option<LumenSpan> {
        let x = (u - self.lateral) / self.half_width;
        (x.abs() < 1.0 && self.half_height > 0.0).then(|| {
            let h = self.half_height * (1.0 - x * x).sqrt();
            LumenSpan {
                top: self.depth - h,
                bottom: self.depth + h,
                wall: self.wall,
            }
        })
    }
}

impl Renderer {
    /// The lumen of vessel `i` of the anatomy in the frame `input` (probe
    /// face at `face`, m) and how it is drawn: its area by its law
    /// ([`Anatomy::lumen_ratio`]) at the tissue pressure at its centre
    /// ([`crate::pressure`]), its height ratio and edge shifts by the
    /// wall-length law ([`crate::widen`]). The reported half-width and
    /// centre are the widened lumen's, its depth moved by `by` (m, in
    /// tissue depth: what its collapsing neighbours carry it by,
    /// [`carried`]).
    pub(super) fn shape_of(
        &self,
        a: &Anatomy,
        i: usize,
        input: &FrameInput,
        face: f64,
        by: f64,
    ) -> (Lumen, LumenShape) {
        let v = &a.vessels()[i].vessel;
        let def = input.deformation;
        // The vessel in the image's frame.
        let lateral = v.lateral - self.pan(input.lateral_offset).0;
        let s = def.surface_at(lateral);
        let centre = column_depth(s, def.bone_depth, v.depth) - face;
        let p = stress_under_rectangle(
            input.probe_pressure.max(0.0),
            self.cfg.probe_width,
            self.cfg.probe_elevation,
            lateral,
            0.0,
            centre.max(0.0),
        );
        let ratio = a.lumen_ratio(i, p, input.time) * self.distension_of(i);
        let shape = lumen_shape(v, ratio, blood_fraction(a, i), side_caps(a, i));
        let c = shape.height_ratio;
        let warp = VesselWarp::new(v, v.lateral, compensated_ratio(c, s, def.bone_depth))
            .with_floor(a.femur_top());
        let (mid, h) = v.chord(v.lateral, 0.0);
        let top = column_depth(s, def.bone_depth, warp.apply(mid - h) + by) - face;
        let bottom = column_depth(s, def.bone_depth, warp.apply(mid + h) + by) - face;
        let lumen = Lumen {
            area: ratio * v.rest_area(),
            rest_area: v.rest_area(),
            tissue_pressure: p,
            lateral: lateral + shape.centre_offset(),
            depth: 0.5 * (top + bottom),
            half_height: 0.5 * (bottom - top),
            half_width: shape.half_width(v.half_width()),
        };
        (lumen, shape)
    }

    /// Sets the studied vein's (vessel 0's) distension: its lumen's height
    /// drawn `factor` times its law's (the rise of the vein's
    /// antero-posterior diameter during a Valsalva strain, issue 17; the
    /// lumen reports follow). Clamped to 1–4 (a diameter up to +300 %, the
    /// flow model's accepted range); a non-finite factor is 1.
    pub fn set_vein_distension(&mut self, factor: f64) {
        self.vein_distension = if factor.is_finite() {
            factor.clamp(1.0, 4.0)
        } else {
            1.0
        };
    }

    /// The distension factor of vessel `i` (the studied vein's, else 1).
    fn distension_of(&self, i: usize) -> f64 {
        if i == 0 {
            self.vein_distension
        } else {
            1.0
        }
    }

    /// The vein's and artery's lumens for `input` (`None` for a phantom).
    /// Lumen areas follow [`Anatomy::vein_lumen_area`] and
    /// [`Anatomy::artery_lumen_area`] at the tissue pressure that reaches
    /// each vessel's centre ([`crate::pressure`]).
    pub fn lumens(&self, input: &FrameInput) -> Result<Option<LumenReport>, ImagingError> {
        check_input(input)?;
        let Some(a) = &self.anatomy else {
            return Ok(None);
        };
        let face = input.deformation.face_depth(0.5 * self.cfg.width);
        Ok(Some(LumenReport {
            vein: self.carried_lumen(a, 0, input, face),
            artery: self.carried_lumen(a, 1, input, face),
        }))
    }

    /// The lumen of vessel `i` of [`Anatomy::vessels`] for `input` (`None`
    /// for a phantom or past the last vessel), by that vessel's own lumen
    /// law at the tissue pressure at its centre.
    pub fn vessel_lumen(
        &self,
        i: usize,
        input: &FrameInput,
    ) -> Result<Option<Lumen>, ImagingError> {
        check_input(input)?;
        let Some(a) = &self.anatomy else {
            return Ok(None);
        };
        if i >= a.vessels().len() {
            return Ok(None);
        }
        let face = input.deformation.face_depth(0.5 * self.cfg.width);
        Ok(Some(self.carried_lumen(a, i, input, face)))
    }

    /// The height ratios `c` of the first `n` vessels' drawn lumens.
    pub(super) fn height_ratios(
        &self,
        a: &Anatomy,
        input: &FrameInput,
        face: f64,
    ) -> ([f64; MAX_VESSELS], usize) {
        let n = a.vessels().len().min(MAX_VESSELS);
        let mut heights = [1.0; MAX_VESSELS];
        for (i, c) in heights.iter_mut().enumerate().take(n) {
            *c = self.shape_of(a, i, input, face, 0.0).1.height_ratio;
        }
        (heights, n)
    }

    /// The lumen of vessel `i` ([`Renderer::shape_of`]) carried by its
    /// collapsing neighbours ([`crate::carry`]).
    fn carried_lumen(&self, a: &Anatomy, i: usize, input: &FrameInput, face: f64) -> Lumen {
        let (heights, n) = self.height_ratios(a, input, face);
        let pan_m = self.pan(input.lateral_offset).0;
        let table = carried(a, &heights[..n], input.deformation, pan_m);
        let by = table.iter().filter_map(|row| row[i]).map(|(_, d)| d).sum();
        self.shape_of(a, i, input, face, by).0
    }
}

/// Which vessel carries which ([`crate::carry`]): `table[k][j]` is the side
/// (`true`: `j` above `k`) and the displacement `D_j` (m, tissue depth,
/// positive downwards) by which vessel `k`'s warp, of height ratio
/// `heights[k]`, carries vessel `j` stacked on it: `k`'s unheld warp at the
/// point of `j`'s wall nearest to `k` in the column through `j`'s centre.
/// `None` where `j` is not stacked on `k`, or `k`'s lumen does not collapse
/// there (its warp's ratio, compensated for the column's strain, ≥ 1).
pub(super) fn carried(
    a: &Anatomy,
    heights: &[f64],
    def: &SectionDeformation,
    pan_m: f64,
) -> [[Option<(bool, f64)>; MAX_VESSELS]; MAX_VESSELS] {
    let mut table = [[None; MAX_VESSELS]; MAX_VESSELS];
    let vs = a.vessels();
    for (k, (carrier, &c)) in vs.iter().zip(heights).enumerate() {
        for (j, other) in vs.iter().enumerate().take(heights.len()) {
            let (v, n) = (&carrier.vessel, &other.vessel);
            let Some(above) = (j != k).then(|| stacked(v, n)).flatten() else {
                continue;
            };
            let s = def.surface_at(n.lateral - pan_m);
            let ratio = compensated_ratio(c, s, def.bone_depth);
            if ratio >= 1.0 {
                continue;
            }
            let w = VesselWarp::new(v, n.lateral, ratio).with_floor(a.femur_top());
            let (mid, h) = n.chord(n.lateral, n.wall);
            let near = if above { mid + h } else { mid - h };
            table[k][j] = Some((above, w.apply(near) - near));
        }
    }
    table
}
