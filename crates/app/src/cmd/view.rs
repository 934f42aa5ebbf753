//! `echothigh view [--device NAME]`: the trainee's web viewer
//! (`echothigh-viewer`), with the device options of `run` (issue 15): with a
//! real device the trainee's hand drives the probe through the one haptic
//! tick, the page's mouse when none is attached.

use super::device_arg::DeviceArgs;
use anyhow::Result;
use echothigh_runtime::scenario::Scenario;

/// Arguments of `echothigh view` (named apart from the viewer's `Args`,
/// which it flattens: clap names an argument group after its struct).
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// The viewer's own options.
    #[command(flatten)]
    pub view: echothigh_viewer::Args,
    /// The device that drives the probe (default: the scenario's `[device]
    /// kind`, itself `simulated`: the page's mouse drives).
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// Runs the viewer; the device is opened first, so that a missing driver
/// is said before the server starts.
pub fn run(args: ViewArgs) -> Result<()> {
    let case = args
        .view
        .case
        .as_deref()
        .map(super::cases::load_case)
        .transpose()?;
    let kind = Scenario::load(args.view.scenario.as_deref())?.device.kind;
    let device = super::live_device::open(&args.device, kind)?;
    let plan = echothigh_viewer::ExamPlan::practice(rand::random())?;
    let session = echothigh_viewer::ExamSession::new(
        plan,
        Box::new(echothigh_viewer::MemorySink::default()),
        true,
    );
    echothigh_viewer::run_with_device(args.view, case, session, device)
}
