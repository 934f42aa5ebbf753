//! The scripted trainee's script (issue 14): a TOML file naming the
//! protocol, how the trainee presses, which sites it presses and how it
//! calls them. Unknown keys are refused; every bad value names its key.
//!
//! ```toml
//! protocol = "whole-leg"     # two-point | three-point | whole-leg
//! calls = "honest"           # honest (from what it saw) | scripted ([[call]])
//! skip = ["fv-mid"]          # protocol sites it does not press (default none)
//!
//! [press]
//! policy = "adequate"        # adequate | target
//! target_force = 10.0        # N: policy "target" stops here
//! max_force = 20.0           # N: the cap of policy "adequate" (default: the patient's exam force)
//! rate = 0.05                # m/s: the hand's setpoint speed into the skin
//! hold = 0.3                 # s: the hold at the deepest point
//!
//! [[call]]                   # calls = "scripted": one per site
//! site = "cfv"
//! finding = "normal"         # normal | acute_dvt | chronic_post_thrombotic | indeterminate
//!
//! [[doppler]]                # optional, any call policy: Doppler calls
//! site = "cfv"               # cfv | popliteal (`echothigh_exam::doppler`)
//! flow = "phasic"            # phasic | continuous | absent
//! augments = true            # the flow rises on a calf squeeze
//! ```
//!
//! `[[doppler]]` is optional (scripts written before it load unchanged):
//! the scripted hand hears no spectrum, so its Doppler calls are the
//! script's, made at the end of the walk.
//!
//! **Honest calls** (review §1 "Positive criterion"): from the presses at
//! the site (within 1 cm, on its vein): walls met → `normal`; not met with
//! the artery deforming (adequate pressure) → `acute_dvt`; not met without
//! adequate pressure → `indeterminate`. A site not pressed gets no call.

use anyhow::{bail, Context, Result};
use echothigh_exam::{DopplerFinding, Finding, FlowPattern, Protocol};
use serde::{Deserialize, Serialize};

/// How the trainee presses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PressPolicy {
    /// Press until the artery begins to deform or the walls meet (what a
    /// sonographer does), up to `max_force`.
    Adequate,
    /// Press to `target_force`, whatever the image shows.
    Target,
}

/// `[press]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PressConfig {
    /// Press policy. Default `adequate`.
    pub policy: PressPolicy,
    /// Force (N) at which a `target` press stops, in [1.5, 40]: above the
    /// detector's 1 N contact threshold with margin, and at most ~40 N,
    /// the top of clinical compression forces (`[exam]` phases' docs).
    /// Default 10 (the default scenario's exam force).
    pub target_force: f64,
    /// The cap (N) of an `adequate` press, in [1.5, 40] when given. Default
    /// (absent): the case's patient's exam force
    /// (`echothigh_anatomy::Patient::exam_force`, 35–50 N on the presets),
    /// the force at which the artery is clearly oval at the leg's hardest
    /// level and the device's renderable limit (issue 12), so that an
    /// adequate press can close a healthy vein at every level of every
    /// preset (the obese leg's need 12–22 N, `tests/suite/coaptation_along_leg.rs`;
    /// the former fixed 20 N stopped short there).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_force: Option<f64>,
    /// The hand's setpoint speed into the skin (m/s), in [0.005, 0.2].
    /// Default 0.05.
    pub rate: f64,
    /// Hold at the deepest point (s), in [0, 5]. Default 0.3 (time to look
    /// at the image under compression).
    pub hold: f64,
}

impl Default for PressConfig {
    fn default() -> Self {
        PressConfig {
            policy: PressPolicy::Adequate,
            target_force: 10.0,
            max_force: None,
            rate: 0.05,
            hold: 0.3,
        }
    }
}

/// How the calls are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CallPolicy {
    /// From what the presses showed (module docs).
    Honest,
    /// As listed in `[[call]]`.
    Scripted,
}

/// One scripted call.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScriptedCall {
    /// The protocol site's name.
    pub site: String,
    /// The finding's name (`normal`, `acute_dvt`,
    /// `chronic_post_thrombotic`, `indeterminate`).
    pub finding: String,
}

/// One scripted Doppler call (`[[doppler]]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScriptedDoppler {
    /// The Doppler site's name (`cfv`, `popliteal`).
    pub site: String,
    /// `phasic`, `continuous` or `absent`.
    pub flow: String,
    /// The flow augments on a calf squeeze.
    pub augments: bool,
}

impl ScriptedDoppler {
    /// The call's finding (the flow name validated by
    /// [`TraineeScript::validate`]).
    pub fn finding(&self) -> Option<DopplerFinding> {
        Some(DopplerFinding {
            flow: FlowPattern::from_name(&self.flow)?,
            augments: self.augments,
        })
    }
}

/// A scripted trainee's script.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TraineeScript {
    /// The protocol's name.
    pub protocol: String,
    /// Call policy. Default `honest`.
    #[serde(default = "honest")]
    pub calls: CallPolicy,
    /// Protocol sites not pressed (names as in the protocol's checklist).
    #[serde(default)]
    pub skip: Vec<String>,
    /// How it presses.
    #[serde(default)]
    pub press: PressConfig,
    /// The scripted calls (`calls = "scripted"`).
    #[serde(default)]
    pub call: Vec<ScriptedCall>,
    /// Doppler calls (optional).
    #[serde(default)]
    pub doppler: Vec<ScriptedDoppler>,
}

fn honest() -> CallPolicy {
    CallPolicy::Honest
}

impl TraineeScript {
    /// Parses and checks a script; `origin` (a path) prefixes the errors.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self> {
        let s: TraineeScript =
            toml::from_str(text).with_context(|| format!("exam script {origin}"))?;
        s.validate()
            .with_context(|| format!("exam script {origin}"))?;
        Ok(s)
    }

    /// The protocol.
    pub fn protocol(&self) -> Protocol {
        Protocol::from_name(&self.protocol).expect("validated")
    }

    /// The scripted finding at `site`, if any.
    pub fn scripted_call(&self, site: &str) -> Option<Finding> {
        self.call
            .iter()
            .rev()
            .find(|c| c.site == site)
            .and_then(|c| Finding::from_name(&c.finding))
    }

    /// Checks every value, naming the key. Site names are checked against
    /// the case's protocol sites when the exam runs (they depend on the
    /// leg for whole-leg).
    pub fn validate(&self) -> Result<()> {
        if Protocol::from_name(&self.protocol).is_none() {
            bail!(
                "protocol = {:?}: unknown (two-point, three-point, whole-leg)",
                self.protocol
            );
        }
        let p = &self.press;
        for (key, v, lo, hi, unit) in [
            ("press.target_force", p.target_force, 1.5, 40.0, "N"),
            (
                "press.max_force",
                p.max_force.unwrap_or(20.0),
                1.5,
                40.0,
                "N",
            ),
            ("press.rate", p.rate, 0.005, 0.2, "m/s"),
            ("press.hold", p.hold, 0.0, 5.0, "s"),
        ] {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                bail!("{key} = {v}: must be in [{lo}, {hi}] {unit}");
            }
        }
        for (i, c) in self.call.iter().enumerate() {
            if Finding::from_name(&c.finding).is_none() {
                bail!(
                    "call[{i}].finding = {:?}: unknown (normal, acute_dvt, chronic_post_thrombotic, indeterminate)",
                    c.finding
                );
            }
        }
        for (i, d) in self.doppler.iter().enumerate() {
            if d.finding().is_none() {
                bail!(
                    "doppler[{i}].flow = {:?}: unknown (phasic, continuous, absent)",
                    d.flow
                );
            }
        }
        if self.calls == CallPolicy::Scripted && self.call.is_empty() {
            bail!("calls = \"scripted\" needs [[call]] entries (site, finding)");
        }
        if self.calls == CallPolicy::Honest && !self.call.is_empty() {
            bail!("call: [[call]] entries need calls = \"scripted\" (calls is \"honest\")");
        }
        Ok(())
    }

    /// Checks the site names of `[[doppler]]` against the Doppler sites
    /// `names`.
    pub fn check_doppler_sites(&self, names: &[&str]) -> Result<()> {
        for (i, d) in self.doppler.iter().enumerate() {
            if !names.contains(&d.site.as_str()) {
                bail!(
                    "doppler[{i}].site = {:?}: not a Doppler site ({})",
                    d.site,
                    list(names)
                );
            }
        }
        Ok(())
    }

    /// Checks the site names of `skip` and `[[call]]` against the
    /// protocol's sites `names`.
    pub fn check_sites(&self, names: &[&str]) -> Result<()> {
        let known = |n: &str| names.contains(&n);
        for (i, s) in self.skip.iter().enumerate() {
            if !known(s) {
                bail!(
                    "skip[{i}] = {s:?}: not a site of {} ({})",
                    self.protocol,
                    list(names)
                );
            }
        }
        for (i, c) in self.call.iter().enumerate() {
            if !known(&c.site) {
                bail!(
                    "call[{i}].site = {:?}: not a site of {} ({})",
                    c.site,
                    self.protocol,
                    list(names)
                );
            }
        }
        Ok(())
    }
}

/// The first few names, for an error.
fn list(names: &[&str]) -> String {
    let mut s = names.iter().take(6).copied().collect::<Vec<_>>().join(", ");
    if names.len() > 6 {
        s.push_str(", …");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        format!(
            "{:#}",
            TraineeScript::from_toml_str(text, "t.toml").unwrap_err()
        )
    }

    /// Each kind of mistake names its key.
    #[test]
    fn bad_scripts_name_the_key() {
        let e = err("protocol = \"whole-leg\"\nprotocl = 1\n");
        assert!(e.contains("protocl"), "{e}");
        let e = err("protocol = \"four-point\"\n");
        assert!(e.contains("protocol") && e.contains("four-point"), "{e}");
        let e = err("protocol = \"two-point\"\n[press]\nmax_force = 90.0\n");
        assert!(e.contains("press.max_force"), "{e}");
        let e = err("protocol = \"two-point\"\n[press]\nforce = 9.0\n");
        assert!(e.contains("force") && e.contains("unknown field"), "{e}");
        let e = err("protocol = \"two-point\"\ncalls = \"scripted\"\n[[call]]\nsite = \"cfv\"\nfinding = \"clot\"\n");
        assert!(e.contains("call[0].finding"), "{e}");
        let e = err("protocol = \"two-point\"\n[[doppler]]\nsite = \"cfv\"\nflow = \"pulsatile\"\naugments = true\n");
        assert!(
            e.contains("doppler[0].flow") && e.contains("pulsatile"),
            "{e}"
        );
        let s = TraineeScript::from_toml_str(
            "protocol = \"two-point\"\n[[doppler]]\nsite = \"fv-mid\"\nflow = \"absent\"\naugments = false\n",
            "t",
        )
        .unwrap();
        let e = format!(
            "{:#}",
            s.check_doppler_sites(&["cfv", "popliteal"]).unwrap_err()
        );
        assert!(e.contains("doppler[0].site") && e.contains("fv-mid"), "{e}");
        let e = err("protocol = \"two-point\"\n[press]\npolicy = \"hard\"\n");
        assert!(e.contains("policy") || e.contains("hard"), "{e}");
        let s =
            TraineeScript::from_toml_str("protocol = \"two-point\"\nskip = [\"fv-mid\"]\n", "t")
                .unwrap();
        let e = format!("{:#}", s.check_sites(&["cfv", "popliteal"]).unwrap_err());
        assert!(e.contains("skip[0]") && e.contains("fv-mid"), "{e}");
    }
}
