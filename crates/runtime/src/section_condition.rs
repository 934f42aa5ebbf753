//! A vein's thrombus state at a section (issue 13), from the anatomy's
//! [`LumenState`] (the blend of a case's segments at the `s` where the
//! plane cuts the vein) to the renderer's per-vein [`VeinCondition`].
//!
//! The mechanical numbers come from the anatomy (fill, compliance of the
//! content and of the open part, distension, wall), the collapse
//! thresholds and the attenuation from the imaging configuration's states:
//! acute content yields between the acute state's onset and full pressures
//! (30 and 150 mmHg by default), chronic content between the chronic
//! state's (60 and 250 mmHg), and the open part between the healthy ones
//! (8 and 35 mmHg); the wall's echo goes from the healthy to the chronic
//! state's with the chronic weight.

use echothigh_anatomy::StructureId;
use echothigh_anatomy::{Layout, LumenState};
use echothigh_imaging::{AnatomyConfig, CollapseLaw, ContentLayout, PostThrombotic, VeinCondition};

/// The seed of a vein's post-thrombotic pattern: its id's name hashed
/// (FNV-1a), so that one vein keeps one pattern as the probe moves along
/// it (no flicker between frames) and the pattern is the same every run.
pub fn pattern_seed(vein: StructureId) -> u64 {
    vein.as_str()
        .bytes()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
        })
}

/// Webs drawn across a chronic vein's lumen (hence three recanalized
/// channels): "webs or synechiae, partly recanalized channels" (issue 13;
/// the count is an estimate, none was found measured).
pub const CHRONIC_WEBS: u8 = 2;

/// The renderer's condition of a vein in `state` (`None` for a healthy
/// vein, which keeps the renderer's healthy defaults); `base` gives the
/// thresholds, echoes and attenuation of the imaging states. Where chronic
/// change outweighs acute thrombus the vein is drawn post-thrombotic
/// ([`PostThrombotic`]: irregular wall, webs, channels) with the pattern of
/// `seed` ([`pattern_seed`]).
pub fn vein_condition(
    state: &LumenState,
    base: &AnatomyConfig,
    seed: u64,
) -> Option<VeinCondition> {
    if *state == LumenState::HEALTHY {
        return None;
    }
    let (h, a, c) = (&base.healthy, &base.acute, &base.chronic);
    let chronic = state.chronic > state.acute;
    let content = if chronic { c } else { a };
    Some(VeinCondition {
        diameter_factor: state.distension,
        wall_thickness: state.wall_thickness,
        wall_echo: h.wall_echo + state.chronic * (c.wall_echo - h.wall_echo),
        fill: state.fill.clamp(0.0, 1.0),
        layout: match state.layout {
            Layout::Mural => ContentLayout::Mural,
            Layout::Central => ContentLayout::Central,
        },
        content_echo: state.echo_db,
        content_attenuation: content.content_attenuation,
        content_law: CollapseLaw {
            onset: content.collapse_onset,
            full: content.collapse_full,
            min_ratio: state.fill_min_ratio,
        },
        open_law: CollapseLaw {
            onset: h.collapse_onset,
            full: h.collapse_full,
            min_ratio: state.open_min_ratio,
        },
        sway: state.sway.clamp(0.0, 1.0),
        post_thrombotic: chronic.then_some(PostThrombotic {
            webs: CHRONIC_WEBS,
            seed,
        }),
    })
}
