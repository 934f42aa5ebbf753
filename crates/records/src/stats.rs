//! The arithmetic of a trainee's record, free of the database: sensitivity
//! and specificity for acute DVT, coverage, pressure adequacy and calls
//! correct, over any set of finished cases (a session, a trainee, a site).
//!
//! Counting rules (issue 14 "Scoring"; fidelity review §3):
//! - a site is *truth positive* when its truth is acute DVT, otherwise
//!   (normal, chronic post-thrombotic change) *truth negative*;
//! - a call is *positive* only when it is acute DVT;
//! - on a positive site, acute DVT is a true positive and anything else —
//!   normal, chronic, **indeterminate, or no call** — is a false negative
//!   (a miss: an inadequate study did not find the clot);
//! - on a negative site, acute DVT is a false positive, normal or chronic
//!   is a true negative, and **indeterminate or no call is neither**: it is
//!   kept out of the specificity (an inadequate study shows nothing to be
//!   normal) and counted apart as `unresolved_negative`, so declining to
//!   call can never raise the specificity.
//!
//! Sensitivity = TP / (TP + FN), specificity = TN / (TN + FP); `None` when
//! the denominator is zero (no site of that truth), never a made-up 0 or 1.

use echothigh_exam::Finding;
use serde::Serialize;

/// Counts of calls against the truth for acute DVT.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Confusion {
    /// Positive sites called acute DVT.
    pub true_positive: u32,
    /// Positive sites called anything else, indeterminate or not called.
    pub false_negative: u32,
    /// Negative sites called normal or chronic.
    pub true_negative: u32,
    /// Negative sites called acute DVT.
    pub false_positive: u32,
    /// Negative sites called indeterminate or not called (out of the
    /// specificity).
    pub unresolved_negative: u32,
}

impl Confusion {
    /// Counts one site: the call made there (`None`: none) and its truth.
    pub fn add(&mut self, call: Option<Finding>, truth: Finding) {
        let called_positive = call.is_some_and(Finding::is_positive);
        let resolved = matches!(call, Some(f) if f != Finding::Indeterminate);
        match (truth.is_positive(), called_positive, resolved) {
            (true, true, _) => self.true_positive += 1,
            (true, false, _) => self.false_negative += 1,
            (false, true, _) => self.false_positive += 1,
            (false, false, true) => self.true_negative += 1,
            (false, false, false) => self.unresolved_negative += 1,
        }
    }

    /// Adds another set of counts.
    pub fn merge(&mut self, o: &Confusion) {
        self.true_positive += o.true_positive;
        self.false_negative += o.false_negative;
        self.true_negative += o.true_negative;
        self.false_positive += o.false_positive;
        self.unresolved_negative += o.unresolved_negative;
    }

    /// TP / (TP + FN), in [0, 1]; `None` without a positive site.
    pub fn sensitivity(&self) -> Option<f64> {
        ratio(self.true_positive, self.true_positive + self.false_negative)
    }

    /// TN / (TN + FP), in [0, 1]; `None` without a resolved negative site.
    pub fn specificity(&self) -> Option<f64> {
        ratio(self.true_negative, self.true_negative + self.false_positive)
    }
}

fn ratio(num: u32, den: u32) -> Option<f64> {
    (den > 0).then(|| f64::from(num) / f64::from(den))
}

/// What the statistics need of one finished case.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CaseOutcome {
    /// The case's coverage, in [0, 1].
    pub coverage: f64,
    /// Calls matching the truth.
    pub calls_correct: u32,
    /// Calls asked for.
    pub calls_total: u32,
    /// Presses in the case.
    pub presses: u32,
    /// Presses with adequate pressure (coapted or artery deformed).
    pub adequate_presses: u32,
    /// Per site: the call (`None`: none) and the truth.
    pub sites: Vec<(String, Option<Finding>, Finding)>,
}

/// The rates of a set of finished cases.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Rates {
    /// Finished cases counted.
    pub cases: u32,
    /// Mean of the cases' coverage, in [0, 1] (`None` without a case).
    pub mean_coverage: Option<f64>,
    /// Σ calls correct / Σ calls asked for, in [0, 1].
    pub calls_correct: Option<f64>,
    /// Σ adequate presses / Σ presses, in [0, 1] (pooled over presses).
    pub pressure_adequacy: Option<f64>,
    /// Acute-DVT sensitivity over every site of the cases.
    pub sensitivity: Option<f64>,
    /// Acute-DVT specificity over every site of the cases.
    pub specificity: Option<f64>,
    /// The counts behind the two.
    pub confusion: Confusion,
}

impl Rates {
    /// The rates of `cases`.
    pub fn of<'a>(cases: impl IntoIterator<Item = &'a CaseOutcome>) -> Rates {
        let (mut n, mut cov, mut correct, mut total, mut presses, mut adequate) =
            (0u32, 0.0, 0u32, 0u32, 0u32, 0u32);
        let mut confusion = Confusion::default();
        for c in cases {
            n += 1;
            cov += c.coverage;
            correct += c.calls_correct;
            total += c.calls_total;
            presses += c.presses;
            adequate += c.adequate_presses;
            for (_, call, truth) in &c.sites {
                confusion.add(*call, *truth);
            }
        }
        Rates {
            cases: n,
            mean_coverage: (n > 0).then(|| cov / f64::from(n)),
            calls_correct: ratio(correct, total),
            pressure_adequacy: ratio(adequate, presses),
            sensitivity: confusion.sensitivity(),
            specificity: confusion.specificity(),
            confusion,
        }
    }
}

/// Per-site counts over `cases`, sites in first-seen order.
pub fn by_site<'a>(cases: impl IntoIterator<Item = &'a CaseOutcome>) -> Vec<(String, Confusion)> {
    let mut out: Vec<(String, Confusion)> = Vec::new();
    for c in cases {
        for (site, call, truth) in &c.sites {
            let i = match out.iter().position(|(s, _)| s == site) {
                Some(i) => i,
                None => {
                    out.push((site.clone(), Confusion::default()));
                    out.len() - 1
                }
            };
            out[i].1.add(*call, *truth);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use Finding::*;

    #[test]
    fn indeterminate_is_a_miss_on_positives_and_out_of_specificity_on_negatives() {
        let mut c = Confusion::default();
        c.add(Some(AcuteDvt), AcuteDvt); // TP
        c.add(Some(Indeterminate), AcuteDvt); // FN
        c.add(None, AcuteDvt); // FN
        c.add(Some(ChronicPostThrombotic), AcuteDvt); // FN
        c.add(Some(Normal), Normal); // TN
        c.add(Some(Normal), ChronicPostThrombotic); // TN (not acute)
        c.add(Some(AcuteDvt), Normal); // FP
        c.add(Some(Indeterminate), Normal); // unresolved
        c.add(None, Normal); // unresolved
        assert_eq!(
            c,
            Confusion {
                true_positive: 1,
                false_negative: 3,
                true_negative: 2,
                false_positive: 1,
                unresolved_negative: 2
            }
        );
        // 1 / (1 + 3) and 2 / (2 + 1), exactly representable or the
        // nearest double of the same quotient.
        assert_eq!(c.sensitivity(), Some(0.25));
        assert_eq!(c.specificity(), Some(2.0 / 3.0));
        assert_eq!(Confusion::default().sensitivity(), None);
    }

    #[test]
    fn rates_pool_presses_and_calls_and_average_coverage() {
        let a = CaseOutcome {
            coverage: 1.0,
            calls_correct: 2,
            calls_total: 3,
            presses: 4,
            adequate_presses: 3,
            sites: vec![("cfv".into(), Some(Normal), Normal)],
        };
        let b = CaseOutcome {
            coverage: 0.5,
            calls_correct: 1,
            calls_total: 1,
            presses: 0,
            adequate_presses: 0,
            sites: vec![("cfv".into(), Some(AcuteDvt), AcuteDvt)],
        };
        let r = Rates::of([&a, &b]);
        assert_eq!(r.cases, 2);
        assert_eq!(r.mean_coverage, Some(0.75)); // (1 + 0.5) / 2
        assert_eq!(r.calls_correct, Some(0.75)); // 3 / 4 calls, not the mean 0.83
        assert_eq!(r.pressure_adequacy, Some(0.75)); // 3 / 4 presses
        assert_eq!((r.sensitivity, r.specificity), (Some(1.0), Some(1.0)));
        let sites = by_site([&a, &b]);
        assert_eq!(sites.len(), 1);
        assert_eq!(sites[0].1.true_positive + sites[0].1.true_negative, 2);
        assert_eq!(Rates::of([]).mean_coverage, None);
    }
}
