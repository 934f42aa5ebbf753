//! The buffer model (paper §4) as published by the model manager, and the
//! lock-free single-slot handoff that carries it to the haptic loop (a triple
//! buffer: the writer never waits, the reader always gets the latest complete
//! value, neither locks nor allocates).

use triple_buffer::{triple_buffer, Input, Output};

use crate::local_model::{LocalModel, ModelParams};

/// One published buffer model: the fitted constraint surface `φ(u, x) = 0`
/// and the local stiffness `k`, with the time of the sample it was fitted to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BufferModel {
    /// Parameters `u` of the local model.
    pub params: ModelParams,
    /// Local stiffness `k`, N/m (paper: "proportional to the local stiffness").
    pub stiffness: f64,
    /// Time of the physics sample the model was fitted to, s (physics clock).
    pub sample_time: f64,
    /// Estimated physics period, s (force shading blends over it).
    pub period: f64,
    /// Publication counter; 0 means "no model yet" (render no force).
    pub sequence: u64,
}

impl BufferModel {
    /// The placeholder before the first fit: `sequence = 0`, zero stiffness.
    pub fn none() -> Self {
        BufferModel {
            params: ModelParams::Plane(crate::local_model::Plane {
                normal: crate::Vec3::y(),
                offset: f64::NEG_INFINITY,
            }),
            stiffness: 0.0,
            sample_time: 0.0,
            period: 0.01,
            sequence: 0,
        }
    }

    /// True for a real model (`sequence > 0`) whose numbers are all usable.
    pub fn is_usable(&self) -> bool {
        self.sequence > 0
            && self.params.is_valid()
            && self.stiffness.is_finite()
            && self.stiffness >= 0.0
            && self.period.is_finite()
            && self.period > 0.0
            && self.sample_time.is_finite()
    }
}

/// Writer side of the handoff (held by the model manager).
pub struct ModelPublisher {
    input: Input<BufferModel>,
}

impl ModelPublisher {
    /// Publishes `model`; wait-free, no allocation.
    pub fn publish(&mut self, model: BufferModel) {
        self.input.write(model);
    }
}

/// Reader side of the handoff (held by the haptic loop).
pub struct ModelReceiver {
    output: Output<BufferModel>,
}

impl ModelReceiver {
    /// The latest published model (wait-free, no allocation).
    pub fn latest(&mut self) -> BufferModel {
        *self.output.read()
    }
}

/// Creates a connected publisher/receiver pair holding `BufferModel::none()`.
pub fn handoff() -> (ModelPublisher, ModelReceiver) {
    let (input, output) = triple_buffer(&BufferModel::none());
    (ModelPublisher { input }, ModelReceiver { output })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latest_wins() {
        let (mut tx, mut rx) = handoff();
        assert_eq!(rx.latest().sequence, 0);
        assert!(!rx.latest().is_usable());
        let mut m = BufferModel::none();
        m.stiffness = 100.0;
        m.params = ModelParams::Plane(crate::local_model::Plane {
            normal: crate::Vec3::y(),
            offset: 0.0,
        });
        for s in 1..=3 {
            m.sequence = s;
            tx.publish(m);
        }
        let got = rx.latest();
        assert_eq!(got.sequence, 3);
        assert!(got.is_usable());
    }
}
