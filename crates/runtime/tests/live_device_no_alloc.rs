//! The live system's per-tick work with a real device allocates nothing
//! (issue 15): [`DeviceLoop::step`] — the one haptic tick on the device, the
//! skin-normal pose of a device without orientation, the device's status
//! handoff — run 20 000 times on the **emulated** Touch (`echothigh-device-emu`'s
//! libHD stand-in; no hardware here), its orientation hidden so that the
//! probe is posed normal to a patient's skin (the leg's path, the costlier
//! one). The counting allocator counts this thread only: the emulator's
//! servo thread is the SDK's, not the tick's.

mod emu;

use echothigh_device::{DeviceFaults, HapticDevice};
use echothigh_devices_hw::{open_hardware, DeviceKind, HardwareConfig, HardwareDevice, Vec3};
use echothigh_runtime::haptic_side::haptic_side_for;
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::live_device::DeviceTick;
use echothigh_runtime::live_system::{DeviceLoop, SkinNormal};
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::tick::HapticTick;
use echothigh_testkit::{count_allocations, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// The emulated Touch as a 3-DoF device (its gimbal ignored).
struct ThreeDof(HardwareDevice);

impl HapticDevice for ThreeDof {
    fn position(&self) -> Vec3 {
        self.0.position()
    }
    fn velocity(&self) -> Vec3 {
        self.0.velocity()
    }
    fn set_force(&mut self, force: Vec3) {
        self.0.set_force(force)
    }
    fn force(&self) -> Vec3 {
        self.0.force()
    }
    fn max_force(&self) -> f64 {
        self.0.max_force()
    }
    fn max_stiffness(&self) -> f64 {
        self.0.max_stiffness()
    }
    fn sampling_rate(&self) -> f64 {
        self.0.sampling_rate()
    }
    fn advance(&mut self, dt: f64) {
        self.0.advance(dt)
    }
    fn faults(&self) -> DeviceFaults {
        self.0.faults()
    }
    fn clutched(&self) -> bool {
        self.0.clutched()
    }
    fn lost(&self) -> Option<u32> {
        self.0.lost()
    }
}

#[test]
fn the_device_loop_step_allocates_nothing() {
    let _g = emu::serial();
    let touch = emu::Touch::load();
    touch.hand([0.0, -20.0, 0.0], 300.0, 5.0);
    let mut s = Scenario::default();
    s.thigh.patient = "average-female".into();
    s.validate().unwrap();
    let device = open_hardware(DeviceKind::Openhaptics, &HardwareConfig::default()).unwrap();
    let (_sink, source) = haptic_side_for(CouplingMode::Buffer, &s).unwrap();
    let period = s.coupling.haptic_period();
    let tick = HapticTick::new(
        Box::new(ThreeDof(device)) as Box<dyn HapticDevice + Send>,
        source,
        s.device.force_scale(),
        None,
        period,
    );
    let (status, mut status_out) = triple_buffer::triple_buffer(&DeviceTick::default());
    let skin = SkinNormal::of(&s).unwrap();
    assert!(matches!(skin, SkinNormal::Leg(..)));
    let mut lp = DeviceLoop::new(tick, (), skin, status, [1.0, 0.0, 0.0, 0.0]);
    lp.step(0.0).unwrap(); // warm-up
    let mut t = 0.0;
    let ((), n) = count_allocations(|| {
        for _ in 0..20_000 {
            t += period;
            assert_eq!(lp.step(t).unwrap(), None);
        }
    });
    assert_eq!(n, 0, "allocations in 20 000 device-loop steps");
    assert_eq!(status_out.read().lost, None);
}
