//! Stage 1 of a frame: the probe face, the skin's displacement in every
//! column, the vessels' lumens and warps, the widening lumens' lateral
//! maps and the edge shadows.

use super::lumens::{carried, VesselLumen};
use super::{check_input, FrameInput, Renderer, NOISE_ROLL};
use crate::anatomy_config::VeinState;
use crate::deformation::column_depth;
use crate::error::ImagingError;
use crate::lateral_map::LateralMap;
use crate::stages::image_depth;
use crate::warp::{compensated_ratio, VesselWarp, MAX_VESSELS};
use crate::widen::{decay_lengths, LumenShape};

impl Renderer {
    /// The image depth (m below the probe face) at which the last frame
    /// ([`Renderer::render`]) drew the tissue point at depth `depth` (m
    /// below the undeformed skin, anatomy frame) in image column `j`: the
    /// column's compression ([`crate::deformation`]) after the vessels'
    /// warps ([`crate::warp`]), before a widening lumen's lateral map
    /// ([`crate::lateral_map`]). Before any frame, the undeformed depth.
    pub fn drawn_depth(&self, j: usize, depth: f64) -> f64 {
        let b = (j + self.field.halo).min(self.bin_u.len() - 1);
        image_depth(&self.geometry, self.surface[b], &self.warps[b], depth)
    }

    /// Stage 1: frame geometry, per-column skin displacement and warps.
    pub(super) fn prepare(&mut self, input: &FrameInput) -> Result<(), ImagingError> {
        let def = input.deformation;
        let face = def.face_depth(0.5 * self.cfg.width);
        self.geometry.face = face;
        self.geometry.bone = def.bone_depth;
        let (pan_m, pan) = self.pan(input.lateral_offset);
        self.pan_columns = pan;
        // Electronic noise changes from frame to frame (deterministically in time).
        let tick = (input.time * 1e3).round().rem_euclid(1e6) as usize;
        self.noise_roll = tick.wrapping_mul(2_654_435_761) % NOISE_ROLL;
        check_input(input)?;
        let mut ratios = [1.0f64; MAX_VESSELS];
        let mut heights = [1.0f64; MAX_VESSELS];
        let mut shapes = [LumenShape::default(); MAX_VESSELS];
        let mut lumens = [VesselLumen::default(); MAX_VESSELS];
        let mut table = [[None; MAX_VESSELS]; MAX_VESSELS];
        let n = match &self.anatomy {
            Some(a) => {
                let vs = a.vessels();
                let (c, n) = self.height_ratios(a, input, face);
                table = carried(a, &c[..n], def, pan_m);
                for (i, r) in ratios.iter_mut().enumerate().take(n) {
                    let by = table.iter().filter_map(|row| row[i]).map(|(_, d)| d).sum();
                    let (l, shape) = self.shape_of(a, i, input, face, by);
                    *r = l.area / vs[i].vessel.rest_area();
                    heights[i] = shape.height_ratio;
                    shapes[i] = shape;
                    lumens[i] = VesselLumen {
                        lateral: l.lateral,
                        depth: l.depth,
                        half_height: l.half_height,
                        half_width: l.half_width,
                        wall: vs[i].vessel.wall,
                    };
                }
                vs.len().min(MAX_VESSELS)
            }
            None => 0,
        };
        self.lumens = lumens;
        self.lumen_count = n;
        // Smoke only in a patent studied vein (blood, not thrombus).
        let patent = self
            .anatomy
            .as_ref()
            .is_some_and(|a| a.state() == VeinState::Healthy && n > 0);
        self.smoke_phase = match &self.smoke {
            Some(s) if patent => Some(s.phase(input.time)),
            _ => None,
        };
        for (b, &u_image) in self.bin_u.iter().enumerate() {
            let s = def.surface_at(u_image);
            self.surface[b] = s;
            let u = u_image + pan_m;
            let set = &mut self.warps[b];
            set.clear();
            if let Some(a) = &self.anatomy {
                let (vs, floor) = (a.vessels(), a.femur_top());
                for (k, (sv, &r)) in vs.iter().zip(&heights[..n]).enumerate() {
                    let mut w =
                        VesselWarp::new(&sv.vessel, u, compensated_ratio(r, s, def.bone_depth))
                            .with_floor(floor);
                    if let Some(c) = sv.condition() {
                        // A floating tail sways with breathing (issue 13).
                        w = w.with_tail(c.fill, c.tail_shift(input.time));
                    }
                    // The vessels stacked on this one ride its decay whole.
                    for (other, carry) in vs.iter().zip(&table[k][..n]) {
                        if let Some((above, d)) = *carry {
                            w = w.carrying(&other.vessel, d, u, above, floor);
                        }
                    }
                    set.push(w);
                }
            }
        }
        self.lateral_maps(&shapes[..n], pan_m);
        self.edge_shadows(&ratios[..n], &shapes[..n], pan_m);
        Ok(())
    }

    /// The lateral maps ([`crate::lateral_map`]) of the widening lumens of
    /// `shapes` (one per vessel): each vessel's band is its walls' depth
    /// span in the frame (through the columns it crosses, after the
    /// warps); the shift fades over the vessel's rest half-height above it
    /// and the same below, ending at the femur's top and at the near wall
    /// of a vessel stacked on it ([`crate::carry::stacked`], through that
    /// vessel's centre column), which it leaves whole.
    fn lateral_maps(&mut self, shapes: &[LumenShape], pan_m: f64) {
        self.map_count = 0;
        let Some(a) = &self.anatomy else {
            return;
        };
        let g = &self.geometry;
        let floor = a.femur_top();
        for (i, (sv, shape)) in a.vessels().iter().zip(shapes).enumerate() {
            if !shape.is_widened() {
                continue;
            }
            let v = &sv.vessel;
            let outer = v.chord_half_width(v.wall);
            let (mut top, mut bottom) = (f64::INFINITY, f64::NEG_INFINITY);
            for (b, &u_image) in self.bin_u.iter().enumerate() {
                let u = u_image + pan_m;
                let (c, h) = v.chord(u, v.wall);
                if h <= 0.0 {
                    continue;
                }
                let (s, w) = (self.surface[b], &self.warps[b]);
                top = top.min(image_depth(g, s, w, c - h));
                bottom = bottom.max(image_depth(g, s, w, c + h));
            }
            if !top.is_finite() || top > bottom {
                continue; // the vessel is outside the window
            }
            let x0 = v.lateral - pan_m;
            let s = self.surface[((x0 - self.bin_u[0]) / self.cfg.pixel_width())
                .round()
                .clamp(0.0, (self.bin_u.len() - 1) as f64)
                as usize];
            let bone = column_depth(s, g.bone, floor) - g.face;
            // The shift fades out before a vessel stacked on this one
            // (`crate::carry`): the lateral map leaves it whole too.
            let (mut up, mut down) = (v.half_height(), v.half_height().min(bone - bottom));
            for other in a.vessels() {
                let n = &other.vessel;
                let Some(above) = crate::carry::stacked(v, n) else {
                    continue;
                };
                let b = (((n.lateral - pan_m - self.bin_u[0]) / self.cfg.pixel_width())
                    .round()
                    .clamp(0.0, (self.bin_u.len() - 1) as f64)) as usize;
                let (mid, h) = n.chord(n.lateral, n.wall);
                let (s, w) = (self.surface[b], &self.warps[b]);
                if above {
                    up = up.min(top - image_depth(g, s, w, mid + h));
                } else {
                    down = down.min(image_depth(g, s, w, mid - h) - bottom);
                }
            }
            self.lateral_maps[self.map_count] = LateralMap::new(
                x0,
                v.half_width(),
                outer,
                shape.shift,
                decay_lengths(a, i),
                (top, bottom),
                up,
                down,
            );
            self.map_count += 1;
        }
    }

    /// The refraction edge shadows of the frame ([`crate::edge_shadow`]):
    /// the two lateral margins of each vessel (its wall's lateral extremes;
    /// lumen area `ratios[i]` of rest), in the image through the column of
    /// each margin, moved outwards with the lumen's widening (`shapes`).
    fn edge_shadows(&mut self, ratios: &[f64], shapes: &[LumenShape], pan_m: f64) {
        self.shadows.clear();
        let Some(a) = &self.anatomy else {
            return;
        };
        let dx = self.cfg.pixel_width();
        let (u0, last) = (self.bin_u[0], self.bin_u.len() - 1);
        for ((sv, &r), shape) in a.vessels().iter().zip(ratios).zip(shapes) {
            let v = &sv.vessel;
            let hw = v.half_width();
            // The vessel's top in the image, through the column at its
            // centre, 1 mm higher for the chord's rise off the centre
            // line in a rotated vessel.
            let (c, h) = v.chord(v.lateral, v.wall);
            let bc = (((v.lateral - pan_m - u0) / dx).round().max(0.0) as usize).min(last);
            let top = image_depth(&self.geometry, self.surface[bc], &self.warps[bc], c - h) - 1e-3;
            for (s, widen) in [(-1.0, shape.shift[0]), (1.0, shape.shift[1])] {
                // 10 µm inside the margin, where the chord exists.
                let ua = v.lateral + s * (hw - 1e-5);
                let ui = v.lateral + s * (v.chord_half_width(v.wall) + widen) - pan_m;
                let rest = ui - s * widen;
                let b = (((rest - u0) / dx).round().max(0.0) as usize).min(last);
                let d = v.chord(ua, 0.0).0;
                let z = image_depth(&self.geometry, self.surface[b], &self.warps[b], d);
                self.shadows.push(ui, z, top, r);
            }
        }
    }
}
