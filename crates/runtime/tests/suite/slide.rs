//! Regression test of the slide of the default exam (the probe once fell
//! through the skin while sliding along the thigh: the exam site was on the
//! held end ring at `z = L/2` and the slide went off the end of the modelled
//! segment). In `direct` coupling (physics at 1 kHz with the device, no
//! haptic model in between), the first slide of the exam must keep the
//! probe on the tissue: the contact force never drops to zero and stays
//! near the held force, and the probe face stays on the deformed surface
//! (the penalty contact's sub-millimetre penetration, not millimetres).

use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::virtual_clock::VirtualRun;
use nalgebra::Vector3;

/// Exam phase codes of `TickRecord::phase` (`runtime::virtual_clock::phase_code` = `tick::phase_code`).
const HOLD: u8 = 2;
const SLIDE: u8 = 3;

fn norm(v: [f64; 3]) -> f64 {
    Vector3::from(v).norm()
}

#[test]
fn first_slide_keeps_the_probe_on_the_tissue() {
    let mut s = Scenario::default();
    s.coupling.mode = CouplingMode::Direct;
    s.run.duration = 4.5;
    s.validate().unwrap();
    let mut run = VirtualRun::new(&s).unwrap();

    // Approach, press and hold (~1.95 s), then the first slide (20 mm at
    // 10 mm/s); the first repetition's release starts ~4.45 s.
    let (mut held, mut held_n) = (0.0, 0usize);
    let (mut f_min, mut f_max) = (f64::INFINITY, 0.0_f64);
    let (mut slide_ticks, mut slide_start, mut slide_end) = (0usize, None, None);
    let mut worst_inside: f64 = 0.0;
    let mut after_slide = false;
    while run.time() < 4.5 && !after_slide {
        run.step_tick().unwrap();
        let r = *run.ticks().last().unwrap();
        let f = norm(r.force);
        assert!(f.is_finite(), "non-finite force at t = {:.3} s", r.t);
        match r.phase {
            HOLD if slide_ticks == 0 && r.holding => {
                held += f;
                held_n += 1;
            }
            SLIDE => {
                slide_ticks += 1;
                slide_start.get_or_insert(Vector3::from(r.device));
                slide_end = Some(Vector3::from(r.device));
                f_min = f_min.min(f);
                f_max = f_max.max(f);
                if slide_ticks % 20 == 0 {
                    let p = Vector3::from(r.device);
                    let d = run.physics_mut().signed_distance(&p).unwrap();
                    worst_inside = worst_inside.min(d);
                }
            }
            _ => after_slide = slide_ticks > 0,
        }
    }
    assert!(held_n > 500, "no hold before the slide ({held_n} ticks)");
    let held = held / held_n as f64;
    assert!(
        (8.0..12.0).contains(&held),
        "held force {held:.2} N, not ~10 N"
    );

    // The slide happened and covered (most of) its 20 mm along z.
    assert!(slide_ticks > 1500, "slide lasted {slide_ticks} ticks");
    let travel = slide_end.unwrap() - slide_start.unwrap();
    assert!(
        travel.z > 0.015,
        "probe slid only {:.1} mm along z",
        travel.z * 1e3
    );

    // The force never drops out and stays within ±40 % of the held force.
    assert!(
        f_min > 0.6 * held,
        "slide force fell to {f_min:.2} N (held {held:.2} N)"
    );
    assert!(
        f_max < 1.4 * held,
        "slide force rose to {f_max:.2} N (held {held:.2} N)"
    );

    // The face stays on the deformed surface (penalty penetration ~0.5 mm
    // at 10 N); the bug put it 5 mm and more inside.
    let p = slide_end.unwrap();
    let end = run.physics_mut().signed_distance(&p).unwrap();
    worst_inside = worst_inside.min(end);
    assert!(
        worst_inside > -0.002,
        "probe {:.2} mm inside the deformed surface during the slide",
        -worst_inside * 1e3
    );
}
