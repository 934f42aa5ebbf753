//! The emulated device's mechanics: a point mass with viscous damping, moved
//! by the motor force and by an optional emulated hand.
//!
//! `m ẍ = F_motor + F_hand − b ẋ`, with `F_hand = k_h (x_h − x) − c_h ẋ` while
//! the hand grips the end-effector, integrated by semi-implicit Euler in
//! sub-steps of at most 100 µs (stable for `b dt / m ≪ 1` and
//! `k_h dt² / m ≪ 1`: with the defaults, 0.013 and 0.0013).

/// State and parameters of the emulated end-effector (SI units, device frame).
#[derive(Debug, Clone, Copy)]
pub struct Arm {
    /// Position (m).
    pub position: [f64; 3],
    /// Velocity (m/s).
    pub velocity: [f64; 3],
    /// Apparent mass at the end-effector (kg).
    pub mass: f64,
    /// Viscous friction (N·s/m).
    pub damping: f64,
    /// Motor force currently applied (N).
    pub motor: [f64; 3],
    /// Emulated hand: target (m), stiffness (N/m), damping (N·s/m); `None` when released.
    pub hand: Option<([f64; 3], f64, f64)>,
}

impl Arm {
    /// An arm at rest at the origin with the given mass (kg) and damping (N·s/m).
    pub const fn new(mass: f64, damping: f64) -> Self {
        Arm {
            position: [0.0; 3],
            velocity: [0.0; 3],
            mass,
            damping,
            motor: [0.0; 3],
            hand: None,
        }
    }

    /// Integrates over `dt` (s) with the current motor force held, in
    /// sub-steps of at most 100 µs.
    pub fn advance(&mut self, dt: f64) {
        if !(dt.is_finite() && dt > 0.0) {
            return;
        }
        let n = (dt / 1e-4).ceil().max(1.0) as usize;
        let h = dt / n as f64;
        for _ in 0..n {
            for i in 0..3 {
                let mut f = self.motor[i] - self.damping * self.velocity[i];
                if let Some((target, k, c)) = self.hand {
                    f += k * (target[i] - self.position[i]) - c * self.velocity[i];
                }
                self.velocity[i] += f / self.mass * h;
                self.position[i] += self.velocity[i] * h;
            }
        }
    }
}
