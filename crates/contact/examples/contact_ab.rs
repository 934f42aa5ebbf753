//! Same-run, interleaved A/B of the contact path (issue 16/18): A is the old
//! path — the contact's Jacobians assembled into two scratch matrices and
//! combined over the whole pattern at every Newton iteration (the
//! `ForceModel` default), and the local stiffness's `K w` from a full
//! assembly of `K` and `B`; B is the current path — direct scaled assembly
//! and the matrix-free `K w`. Two identical models step the same probe
//! press (0–10 mm at 1 Hz on the mid-thigh, h = 10 ms), alternating step by
//! step, each step timed in the thread's CPU time; the queries (the Schur
//! complement stiffness) are timed apart.
//!
//! `cargo run --release -p echothigh-contact --example contact_ab [steps]`

use echothigh_contact::{
    ContactParams, ContactSet, ContactSpring, LocalStiffness, PenaltyContact, Probe,
};
use echothigh_model::{BlockSparse, ForceModel, ModelConfig, NoExtraForce, ThighModel, Vec3};

/// Forwards everything but `add_scaled_jacobians`: the trait's default runs.
struct Unfused<'a>(&'a mut dyn ForceModel);

impl ForceModel for Unfused<'_> {
    fn add_forces(&mut self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]) {
        self.0.add_forces(x, v, f);
    }
    fn add_jacobians(&mut self, x: &[Vec3], v: &[Vec3], k: &mut BlockSparse, b: &mut BlockSparse) {
        self.0.add_jacobians(x, v, k, b);
    }
    fn max_step_fraction(&self, x: &[Vec3], dx: &[Vec3]) -> f64 {
        self.0.max_step_fraction(x, dx)
    }
}

/// One side of the comparison.
struct Side {
    model: ThighModel,
    contact: PenaltyContact,
    set: ContactSet,
    local: LocalStiffness,
    k: BlockSparse,
    b: BlockSparse,
    w: Vec<Vec3>,
    kw: Vec<Vec3>,
    rhs: Vec<Vec3>,
    step_us: Vec<f64>,
    query_us: Vec<f64>,
    stiffness: f64,
}

impl Side {
    fn new(config: &ModelConfig) -> Self {
        let model = ThighModel::new(config).expect("valid configuration");
        let n = model.node_count();
        let contact = PenaltyContact::new(&model, Probe::default(), ContactParams::default());
        Side {
            local: LocalStiffness::new(&model),
            set: ContactSet::with_capacity(n),
            k: model.pattern().clone(),
            b: model.pattern().clone(),
            w: vec![Vec3::zeros(); n],
            kw: vec![Vec3::zeros(); n],
            rhs: vec![Vec3::zeros(); n],
            model,
            contact,
            step_us: Vec::new(),
            query_us: Vec::new(),
            stiffness: 0.0,
        }
    }

    fn step(&mut self, old: bool, pose: nalgebra::Isometry3<f64>, vel: Vec3, h: f64, timed: bool) {
        let c0 = thread_cpu_us();
        self.contact.set_probe(pose, vel);
        let (x, v) = (
            self.model.positions().to_vec(),
            self.model.velocities().to_vec(),
        );
        self.contact.prepare(&x, &v, h);
        if old {
            self.model.step(h, &mut Unfused(&mut self.contact));
        } else {
            self.model.step(h, &mut self.contact);
        }
        let c1 = thread_cpu_us();
        // The Schur-complement query on the contact springs.
        let (x, v) = (self.model.positions(), self.model.velocities());
        self.contact.prepare(x, v, 0.0);
        self.set.reset(self.contact.direction());
        let c = self.contact.params().stiffness * self.contact.samples().1;
        let (set, contact) = (&mut self.set, &self.contact);
        contact.for_each_contact(x, v, |s, _| {
            set.springs.push(ContactSpring {
                nodes: s.nodes,
                beta: s.beta,
                blocks: *contact.triangle_blocks(s.triangle),
                c,
            })
        });
        if !self.set.springs.is_empty() {
            self.stiffness = if old {
                self.old_stiffness()
            } else {
                self.local.compute(&mut self.model, &mut self.set).0
            };
        }
        let c2 = thread_cpu_us();
        if timed {
            self.step_us.push(c1 - c0);
            self.query_us.push(c2 - c1);
        }
    }

    /// The old query: solve through the default assembly, then `K w` from a
    /// full assembly of the tissue's `K` and `B`.
    fn old_stiffness(&mut self) -> f64 {
        let dir = self.set.direction;
        self.rhs.fill(Vec3::zeros());
        for s in &self.set.springs {
            for (&m, &b) in s.nodes.iter().zip(&s.beta) {
                self.rhs[m] += (s.c * b) * dir;
            }
        }
        self.model
            .solve_stiffness(&mut Unfused(&mut self.set), &self.rhs, &mut self.w);
        self.model
            .jacobians(&mut NoExtraForce, &mut self.k, &mut self.b);
        self.k.mul_vec(&self.w, &mut self.kw);
        let fixed = self.model.fixed();
        let mut k = 0.0;
        for (m, r) in self.rhs.iter().enumerate() {
            if !fixed[m] && *r != Vec3::zeros() {
                k -= self.kw[m].dot(&dir);
            }
        }
        k
    }
}

/// Nearest-rank median (the lower of the middle two); 0 if empty.
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len().saturating_sub(1) / 2).copied().unwrap_or(0.0)
}

/// CPU time consumed by this thread (µs).
fn thread_cpu_us() -> f64 {
    cpu_time::ThreadTime::now().as_duration().as_secs_f64() * 1e6
}

fn main() {
    let steps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(200);
    for (nt, nz) in [(48usize, 21usize), (128, 79)] {
        let mut config = ModelConfig::default();
        config.thigh.n_theta = nt;
        config.thigh.n_z = nz;
        let h = config.integrator.time_step;
        let top = config.thigh.semi_axis_y;
        let (mut a, mut b) = (Side::new(&config), Side::new(&config));
        let warmup = 10;
        let mut last = Probe::exam_pose(Vec3::new(0.0, top, 0.0));
        let mut max_dx: f64 = 0.0;
        for i in 0..warmup + steps {
            let t = (i + 1) as f64 * h;
            let depth = 0.010 * 0.5 * (1.0 - (std::f64::consts::TAU * t).cos());
            let pose = Probe::exam_pose(Vec3::new(0.0, top - depth, 0.0));
            let vel = (pose.translation.vector - last.translation.vector) / h;
            last = pose;
            // Alternate which side goes first, so neither always runs on a warm cache.
            if i % 2 == 0 {
                a.step(true, pose, vel, h, i >= warmup);
                b.step(false, pose, vel, h, i >= warmup);
            } else {
                b.step(false, pose, vel, h, i >= warmup);
                a.step(true, pose, vel, h, i >= warmup);
            }
            let dx = a
                .model
                .positions()
                .iter()
                .zip(b.model.positions())
                .map(|(p, q)| (p - q).amax())
                .fold(0.0, f64::max);
            max_dx = max_dx.max(dx);
        }
        let n = a.model.node_count();
        let (sa, qa) = (median(&mut a.step_us), median(&mut a.query_us));
        let (sb, qb) = (median(&mut b.step_us), median(&mut b.query_us));
        println!(
            "{{\"nodes\": {n}, \"steps\": {steps}, \"old_step_cpu_median_us\": {sa:.1}, \"new_step_cpu_median_us\": {sb:.1}, \"step_ratio_old_over_new\": {:.3}, \"old_query_cpu_median_us\": {qa:.1}, \"new_query_cpu_median_us\": {qb:.1}, \"query_ratio_old_over_new\": {:.3}, \"new_steps_plus_queries_per_s\": {:.1}, \"max_position_difference_m\": {max_dx:e}, \"last_stiffness_old_new\": [{}, {}]}}",
            sa / sb,
            qa / qb,
            1e6 / (sb + qb),
            a.stiffness,
            b.stiffness
        );
    }
}
