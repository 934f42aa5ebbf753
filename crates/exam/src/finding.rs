//! What a trainee calls at a site, and what the truth is there.

use serde::{Deserialize, Serialize};

/// A call on a vein segment (issue 14 "Calls"), and the truth it is scored
/// against: a case's ground-truth piece maps onto one of the first three.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Finding {
    /// Compresses fully (walls meet): no thrombus.
    Normal,
    /// Acute deep vein thrombosis (acute occlusive, non-occlusive or
    /// free-floating thrombus).
    AcuteDvt,
    /// Chronic post-thrombotic change (rigid, thick-walled, recanalized).
    ChronicPostThrombotic,
    /// The study there is inadequate (pressure not adequate, site not
    /// seen): the trainee declines to call it.
    Indeterminate,
}

impl Finding {
    /// Every finding, in the order the page lists them.
    pub const ALL: [Finding; 4] = [
        Finding::Normal,
        Finding::AcuteDvt,
        Finding::ChronicPostThrombotic,
        Finding::Indeterminate,
    ];

    /// The name used in scripts, JSON and the database.
    pub fn name(self) -> &'static str {
        match self {
            Finding::Normal => "normal",
            Finding::AcuteDvt => "acute_dvt",
            Finding::ChronicPostThrombotic => "chronic_post_thrombotic",
            Finding::Indeterminate => "indeterminate",
        }
    }

    /// The finding named `name` ([`Finding::name`]).
    pub fn from_name(name: &str) -> Option<Finding> {
        Finding::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The truth of a ground-truth piece of kind `kind` (`normal` or a
    /// thrombus kind's name of `echothigh_anatomy::ThrombusKind`): acute
    /// kinds are acute DVT, `chronic` is post-thrombotic change. `None` for
    /// an unknown kind.
    pub fn from_truth_kind(kind: &str) -> Option<Finding> {
        match kind {
            "normal" => Some(Finding::Normal),
            "acute_occlusive" | "acute_non_occlusive" | "free_floating" => Some(Finding::AcuteDvt),
            "chronic" => Some(Finding::ChronicPostThrombotic),
            _ => None,
        }
    }

    /// Whether this call is positive for acute DVT (the sensitivity and
    /// specificity of §3 count acute DVT against everything else).
    pub fn is_positive(self) -> bool {
        self == Finding::AcuteDvt
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_truth_kinds_map() {
        for f in Finding::ALL {
            assert_eq!(Finding::from_name(f.name()), Some(f));
        }
        assert_eq!(Finding::from_name("thrombus"), None);
        // Every thrombus kind the anatomy writes in a ground truth maps.
        for k in echothigh_anatomy::ThrombusKind::ALL {
            assert!(Finding::from_truth_kind(k.name()).is_some(), "{}", k.name());
        }
        assert_eq!(Finding::from_truth_kind("normal"), Some(Finding::Normal));
        assert_eq!(
            Finding::from_truth_kind("chronic"),
            Some(Finding::ChronicPostThrombotic)
        );
    }
}
