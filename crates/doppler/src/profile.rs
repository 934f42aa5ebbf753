//! Velocity profiles across a lumen.
//!
//! Venous flow is laminar: Re = ρ v̄ D / μ = 1060 · 0.1 · 0.01 / 0.0035
//! ≈ 300, far below 2000 (blood ρ = 1060 kg/m³, μ = 3.5 mPa·s; CFV 10 mm,
//! mean 10 cm/s), so the steady Poiseuille (parabolic) profile is the
//! default for veins. Arterial flow at the heart rate has a Womersley
//! number α = R √(ωρ/μ) ≈ 4 in the femoral artery, whose profile is
//! blunt: a plug profile approximates it.

use serde::{Deserialize, Serialize};

/// A velocity profile across a circular (or elliptic, by normalized
/// radius) lumen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// Poiseuille: `v(ρ) = v_c (1 − ρ²)`, mean `v_c / 2`.
    #[default]
    Parabolic,
    /// Uniform: `v(ρ) = v_c`.
    Plug,
}

impl Profile {
    /// Velocity at normalized radius `rho` (0 centre, 1 wall) for a
    /// centreline velocity `vc` (m/s); 0 outside the lumen.
    pub fn velocity(self, vc: f64, rho: f64) -> f64 {
        if rho > 1.0 {
            return 0.0;
        }
        match self {
            Profile::Parabolic => vc * (1.0 - rho * rho),
            Profile::Plug => vc,
        }
    }

    /// Area-mean velocity over the centreline velocity: ½ or 1.
    pub fn mean_ratio(self) -> f64 {
        match self {
            Profile::Parabolic => 0.5,
            Profile::Plug => 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The area mean of the parabolic profile, `∫₀¹ (1 − ρ²) 2ρ dρ`, is ½
    /// (midpoint rule with 10⁴ steps: error ~1e-8).
    #[test]
    fn parabolic_area_mean_is_half() {
        let n = 10_000;
        let h = 1.0 / n as f64;
        let m: f64 = (0..n)
            .map(|i| {
                let r = (i as f64 + 0.5) * h;
                Profile::Parabolic.velocity(1.0, r) * 2.0 * r * h
            })
            .sum();
        assert!((m - Profile::Parabolic.mean_ratio()).abs() < 1e-6);
    }
}
