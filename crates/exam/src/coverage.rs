//! Coverage (issue 14 "Coverage"): the deep-vein path cut into 2 cm bins,
//! each marked by the presses over it, and the share of a protocol's bins
//! that were examined.
//!
//! The strip follows the deep veins from the inguinal ligament to the
//! popliteal trifurcation ([`crate::protocol::whole_leg_range`]); each bin
//! belongs to the deep vein at its centre (cfv → fv → pv), so a press
//! counts for a bin only when the vein under the probe is that bin's vein
//! (a press on the GSV taken for the FV examines no FV bin: review §1
//! "What novices get wrong", wrong vessel).
//!
//! **A bin's state from its presses**, strongest first:
//! [`BinState::Closed`] beats [`BinState::NotClosed`] beats
//! [`BinState::InadequatePressure`] beats [`BinState::NotExamined`]. A
//! press that brought the walls together is conclusive for compressibility
//! there (only a patent, thrombus-free lumen coapts); a press that did not,
//! even with the artery deforming, may have been off-centre or on the
//! bin's edge, so a later closure supersedes it. A press with inadequate
//! pressure shows only that the bin was visited.

use crate::protocol::{bin_count, whole_leg_range, ProtocolSite, WHOLE_LEG_SPACING};
use crate::{BinState, CompressionEvent, CoverageBin};
use echothigh_anatomy::Anatomy;

/// Rank of a state in the precedence above (higher wins).
fn rank(s: BinState) -> u8 {
    match s {
        BinState::NotExamined => 0,
        BinState::InadequatePressure => 1,
        BinState::NotClosed => 2,
        BinState::Closed => 3,
    }
}

/// What one press shows: closed if the walls met, else not closed if the
/// artery deformed (adequate pressure), else inadequate pressure.
pub fn event_state(e: &CompressionEvent) -> BinState {
    if e.coapted {
        BinState::Closed
    } else if e.artery_deformed {
        BinState::NotClosed
    } else {
        BinState::InadequatePressure
    }
}

/// Whether a bin in `state` was examined with adequate pressure (closed, or
/// not closed with the artery deforming).
pub fn is_covered(state: BinState) -> bool {
    matches!(state, BinState::Closed | BinState::NotClosed)
}

/// The coverage strip of one leg.
#[derive(Debug, Clone, PartialEq)]
pub struct Coverage {
    bins: Vec<CoverageBin>,
}

impl Coverage {
    /// The strip of `anatomy`'s deep-vein path, every bin not examined.
    pub fn new(anatomy: &Anatomy) -> Coverage {
        let (lo, hi) = whole_leg_range(anatomy);
        let bins = (0..bin_count(lo, hi))
            .map(|k| {
                let s_start = lo + k as f64 * WHOLE_LEG_SPACING;
                let s_end = s_start + WHOLE_LEG_SPACING;
                CoverageBin {
                    vein: anatomy
                        .deep_vein_at(0.5 * (s_start + s_end))
                        .as_str()
                        .to_string(),
                    s_start,
                    s_end,
                    state: BinState::NotExamined,
                }
            })
            .collect();
        Coverage { bins }
    }

    /// The bins, groin to knee.
    pub fn bins(&self) -> &[CoverageBin] {
        &self.bins
    }

    /// The index of the bin over `s` on `vein`, if any.
    pub fn bin_at(&self, vein: &str, s: f64) -> Option<usize> {
        self.bins
            .iter()
            .position(|b| b.vein == vein && s >= b.s_start && s < b.s_end)
    }

    /// Marks the bin under `e` (its vein at its `s`) with what it showed,
    /// keeping the stronger state. Returns the bin's index, `None` when the
    /// press was over no bin of the strip (another vein, or none).
    pub fn apply(&mut self, e: &CompressionEvent) -> Option<usize> {
        let i = self.bin_at(e.vein.as_deref()?, e.s)?;
        let new = event_state(e);
        let b = &mut self.bins[i];
        if rank(new) > rank(b.state) {
            b.state = new;
        }
        Some(i)
    }

    /// The bins a protocol examines: all of them for whole-leg, else the bin
    /// under each of `sites`.
    pub fn protocol_bins(&self, sites: &[ProtocolSite]) -> Vec<usize> {
        let mut v: Vec<usize> = sites
            .iter()
            .filter_map(|x| self.bin_at(&x.vein, x.s))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The share of `sites`' bins examined with adequate pressure
    /// ([`is_covered`]), in [0, 1]; 0 without bins.
    pub fn share(&self, sites: &[ProtocolSite]) -> f64 {
        let bins = self.protocol_bins(sites);
        if bins.is_empty() {
            return 0.0;
        }
        let n = bins
            .iter()
            .filter(|&&i| is_covered(self.bins[i].state))
            .count();
        n as f64 / bins.len() as f64
    }

    /// Marks each checklist item done when its bin is covered.
    pub fn mark_done(&self, sites: &mut [ProtocolSite]) {
        for x in sites {
            x.done = self
                .bin_at(&x.vein, x.s)
                .is_some_and(|i| is_covered(self.bins[i].state));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Protocol;
    use echothigh_anatomy::Patient;

    fn press(vein: &str, s: f64, coapted: bool, artery: bool) -> CompressionEvent {
        CompressionEvent {
            t_start: 0.0,
            t_end: 1.0,
            vein: Some(vein.into()),
            s,
            peak_force: 10.0,
            min_lumen_ratio: if coapted { 0.0 } else { 0.5 },
            artery_deformed: artery,
            coapted,
            slide: 0.0,
            force_trace: vec![],
        }
    }

    /// The precedence: whatever the order of the presses over one bin, the
    /// strongest state stays; a press on another vein marks nothing; the
    /// whole-leg share counts closed and not-closed bins only.
    #[test]
    fn states_keep_the_strongest_and_share_counts_adequate_bins() {
        let a = Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap();
        let sites = Protocol::WholeLeg.sites(&a);
        let orders = [
            [(false, false), (false, true), (true, false)],
            [(true, false), (false, true), (false, false)],
            [(false, true), (true, false), (false, false)],
        ];
        for order in orders {
            let mut c = Coverage::new(&a);
            for (co, ar) in order {
                assert_eq!(c.apply(&press("fv", 0.191, co, ar)), Some(9));
            }
            assert_eq!(c.bins()[9].state, BinState::Closed);
        }
        let mut c = Coverage::new(&a);
        assert_eq!(c.apply(&press("gsv", 0.191, true, true)), None);
        assert_eq!(c.apply(&press("fv", 0.031, true, true)), None, "cfv there");
        c.apply(&press("fv", 0.15, false, false));
        assert_eq!(c.share(&sites), 0.0);
        c.apply(&press("fv", 0.17, false, true));
        c.apply(&press("cfv", 0.01, true, false));
        let n = sites.len() as f64;
        assert!((c.share(&sites) - 2.0 / n).abs() < 1e-15);
        let mut list = sites.clone();
        c.mark_done(&mut list);
        let done: Vec<&str> = list
            .iter()
            .filter(|x| x.done)
            .map(|x| x.name.as_str())
            .collect();
        assert_eq!(done, ["cfv@10mm", "fv@170mm"]);
        // Two-point: the bins under its two sites only (the CFV site at the
        // SFJ, 20 mm, is in the second bin, which nothing examined yet).
        let two = Protocol::TwoPoint.sites(&a);
        assert_eq!(c.protocol_bins(&two).len(), 2);
        assert_eq!(c.share(&two), 0.0);
        c.apply(&press("cfv", 0.025, true, false));
        assert_eq!(c.share(&two), 0.5);
    }
}
