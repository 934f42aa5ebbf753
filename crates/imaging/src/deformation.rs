//! Deformation coupling: how the physics' deformation under the probe moves
//! the points of the section.
//!
//! The physical model (paper §3) supports the surface with normal springs
//! between each surface node and its anchor on the femur. A column of tissue
//! under a surface displacement `s(u)` therefore compresses uniformly between
//! the skin and the femur: a point at depth `d` below the undeformed skin
//! moves inwards by
//!
//! `w(u, d) = s(u) (1 − d / B)` for `d < B`, and 0 below,
//!
//! where `B` is the femur's depth (the springs' anchors). Its deformed depth
//! below the undeformed skin is `y = d + w(u, d)`. Lateral motion is not
//! modelled (the normal springs act along the depth). The vessels' own
//! collapse is superposed by [`VesselWarp`](crate::warp::VesselWarp).

use crate::error::ImagingError;

/// Samples of the skin's inward displacement along the image section, filled
/// by the application from the physical model.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionDeformation {
    /// Lateral positions of the samples (m, from the probe's centre), strictly increasing.
    pub lateral: Vec<f64>,
    /// Inward displacement of the skin at each sample (m, ≥ 0 under the probe).
    pub surface_displacement: Vec<f64>,
    /// Depth of the femur below the skin at rest (m): where the column's
    /// compression ends.
    pub bone_depth: f64,
}

impl SectionDeformation {
    /// No deformation (the probe just touching the skin).
    pub fn rest(bone_depth: f64) -> Self {
        SectionDeformation {
            lateral: vec![-1.0, 1.0],
            surface_displacement: vec![0.0, 0.0],
            bone_depth,
        }
    }

    /// A flat probe of width `probe_width` (m) pressed `indentation` (m) into
    /// the skin, with a raised-cosine roll-off of half-width `edge_width` (m)
    /// around each edge of the face (the skin under the last millimetres of
    /// the face is slightly less displaced, as on a curved thigh), sampled
    /// every 0.25 mm over twice the probe's width.
    ///
    /// `s(u) = δ` for `|u| ≤ w/2 − e`; `δ (1 + cos(π (|u| − w/2 + e)/(2e)))/2`
    /// up to `|u| = w/2 + e`; 0 beyond.
    pub fn flat_press(
        indentation: f64,
        probe_width: f64,
        edge_width: f64,
        bone_depth: f64,
    ) -> Result<Self, ImagingError> {
        let p = "flat_press";
        ImagingError::positive(p, "probe_width", probe_width)?;
        ImagingError::non_negative(p, "edge_width", edge_width)?;
        ImagingError::positive(p, "bone_depth", bone_depth)?;
        ImagingError::non_negative(p, "indentation", indentation)?;
        if indentation >= bone_depth {
            return Err(ImagingError::invalid(
                p,
                "indentation",
                indentation,
                "must be less than bone_depth",
            ));
        }
        if edge_width >= 0.5 * probe_width {
            return Err(ImagingError::invalid(
                p,
                "edge_width",
                edge_width,
                "must be less than half the probe width",
            ));
        }
        let step = 0.25e-3;
        let n = (2.0 * probe_width / step).round() as usize + 1;
        let start = -probe_width;
        let inner = 0.5 * probe_width - edge_width;
        let mut lateral = Vec::with_capacity(n);
        let mut disp = Vec::with_capacity(n);
        for i in 0..n {
            let u = start + i as f64 * step;
            let a = u.abs();
            let s = if a <= inner {
                indentation
            } else if edge_width > 0.0 && a < inner + 2.0 * edge_width {
                let x = (a - inner) / (2.0 * edge_width);
                0.5 * indentation * (1.0 + (std::f64::consts::PI * x).cos())
            } else {
                0.0
            };
            lateral.push(u);
            disp.push(s);
        }
        Ok(SectionDeformation {
            lateral,
            surface_displacement: disp,
            bone_depth,
        })
    }

    /// Checks the samples: at least two, equal lengths, finite, strictly
    /// increasing positions, displacements in `[0, bone_depth)`.
    pub fn validate(&self) -> Result<(), ImagingError> {
        let bad = |field, reason| Err(ImagingError::Input { field, reason });
        if self.lateral.len() < 2 {
            return bad("deformation.lateral", "needs at least two samples");
        }
        if self.lateral.len() != self.surface_displacement.len() {
            return bad(
                "deformation.surface_displacement",
                "must have as many samples as lateral",
            );
        }
        if !(self.bone_depth.is_finite() && self.bone_depth > 0.0) {
            return bad("deformation.bone_depth", "must be finite and > 0");
        }
        if self.lateral.iter().any(|u| !u.is_finite())
            || self.lateral.windows(2).any(|w| w[1] <= w[0])
        {
            return bad(
                "deformation.lateral",
                "must be finite and strictly increasing",
            );
        }
        if self
            .surface_displacement
            .iter()
            .any(|&s| !(s.is_finite() && s > -1e-9 && s < self.bone_depth))
        {
            return bad(
                "deformation.surface_displacement",
                "must be finite, >= 0 and < bone_depth",
            );
        }
        Ok(())
    }

    /// Skin displacement at `u` (m), linearly interpolated, held constant
    /// beyond the first and last samples.
    pub fn surface_at(&self, u: f64) -> f64 {
        let x = &self.lateral;
        let s = &self.surface_displacement;
        let n = x.len();
        if u <= x[0] {
            return s[0].max(0.0);
        }
        if u >= x[n - 1] {
            return s[n - 1].max(0.0);
        }
        let i = x.partition_point(|&xi| xi <= u) - 1;
        let t = (u - x[i]) / (x[i + 1] - x[i]);
        (s[i] + t * (s[i + 1] - s[i])).max(0.0)
    }

    /// Depth of the probe face below the undeformed skin (m): the largest
    /// skin displacement over `|u| ≤ half_width` (the flat face touches the
    /// skin where it is pushed in the most).
    pub fn face_depth(&self, half_width: f64) -> f64 {
        let mut face = self
            .surface_at(-half_width)
            .max(self.surface_at(half_width));
        for (&u, &s) in self.lateral.iter().zip(&self.surface_displacement) {
            if u.abs() <= half_width {
                face = face.max(s);
            }
        }
        face
    }
}

/// Deformed depth below the undeformed skin (m) of the tissue point at depth
/// `depth` (m) in a column whose skin is displaced by `surface` (m), with
/// the femur at `bone_depth` (m): `y = d + s (1 − d/B)` above the femur.
#[inline]
pub fn column_depth(surface: f64, bone_depth: f64, depth: f64) -> f64 {
    if depth < bone_depth {
        depth + surface * (1.0 - depth / bone_depth)
    } else {
        depth
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_press_is_flat_under_the_face_and_smooth_at_the_edges() {
        let d = SectionDeformation::flat_press(0.01, 0.04, 1.5e-3, 0.04).unwrap();
        d.validate().unwrap();
        assert!((d.surface_at(0.0) - 0.01).abs() < 1e-15);
        assert!((d.surface_at(0.018) - 0.01).abs() < 1e-15);
        assert!((d.surface_at(0.02) - 0.005).abs() < 1e-9);
        assert!(d.surface_at(0.03) == 0.0);
        assert!((d.face_depth(0.02) - 0.01).abs() < 1e-15);
        assert!(SectionDeformation::flat_press(0.05, 0.04, 1e-3, 0.04).is_err());
    }

    #[test]
    fn column_compresses_uniformly_to_the_bone() {
        let (s, b) = (0.01, 0.04);
        assert_eq!(column_depth(s, b, 0.0), s);
        assert!((column_depth(s, b, b) - b).abs() < 1e-15);
        assert_eq!(column_depth(s, b, 0.05), 0.05);
        // Uniform strain: equal material intervals shrink by the same factor.
        let e1 = column_depth(s, b, 0.02) - column_depth(s, b, 0.01);
        let e2 = column_depth(s, b, 0.03) - column_depth(s, b, 0.02);
        assert!((e1 - e2).abs() < 1e-15 && (e1 - 0.01 * (1.0 - s / b)).abs() < 1e-15);
    }

    #[test]
    fn bad_input_is_named() {
        let mut d = SectionDeformation::rest(0.04);
        d.lateral[1] = -2.0;
        let e = d.validate().unwrap_err().to_string();
        assert!(e.contains("deformation.lateral"), "{e}");
        let mut d = SectionDeformation::rest(0.04);
        d.surface_displacement[0] = f64::NAN;
        assert!(d
            .validate()
            .unwrap_err()
            .to_string()
            .contains("surface_displacement"));
    }
}
