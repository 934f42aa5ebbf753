//! The case generator (`echothigh cases generate`): new cases drawn from
//! documented distributions, deterministic per seed (ChaCha8).
//!
//! Distributions (sources: `../shared/reference/cus-exam-fidelity.md`, "the
//! reference"; Markel et al., Arch Surg 1992;127:305, duplex of 209 DVTs,
//! "Markel"; Adhikari et al., Ann Emerg Med 2015, 362 DVTs, "Adhikari";
//! De Maeseneer et al., EJVES 2015, 1,338 DVTs, "De Maeseneer"):
//! - **Positive** (acute DVT) with probability `prevalence`: practice ~0.5,
//!   realistic 0.10–0.15 (DVT among suspected patients: 9.7 %, 14.7 %,
//!   16 %, 6.4 %; reference row 32). [`PRACTICE`], [`REALISTIC`].
//! - **Patient**: `lean-male`, `average-female`, `obese` with probabilities
//!   0.35, 0.40, 0.25 (estimate); duplicated femoral vein 0.197 (pooled
//!   prevalence, reference row 26); inguinal lymph node 0.10 and tense
//!   muscle 0.10 (estimates).
//! - **Pattern of a positive case** ([`PATTERNS`]): isolated popliteal,
//!   femoral, common femoral and profunda thrombi are 14.6 %, 5.5 %, 1.4 %,
//!   0.8 % of all DVTs (Adhikari), i.e. 20.3 %, 7.6 %, 1.9 %, 1.1 % of the
//!   DVTs above the calf once the 28 % isolated calf DVTs (De Maeseneer)
//!   are set aside (÷ 0.72); the remaining 69.1 % are multisegment, split
//!   38 : 34.5 between iliofemoral-type (CFV down the FV) and
//!   femoropopliteal (FV into the PV) as in De Maeseneer; when the leg has
//!   a duplicated FV, an FV thrombus lies in one limb (fv2) with
//!   probability ½ (estimate).
//! - **Kind** of each acute segment: total occlusion 82 %, partial 18 %
//!   (Markel); of the occlusive ones with a proximal end in the CFV or FV,
//!   10 % carry a free-floating tail (estimate).
//! - **Extent**: an isolated segment is 3–8 cm long (uniform; estimate),
//!   placed uniformly on its vein; multisegment thrombi span whole veins as
//!   in [`PATTERNS`].
//! - **Echogenicity** of acute content: 75 % near-anechoic, uniform in
//!   [−50, −38] dB re muscle, 25 % mildly echogenic, uniform in [−38, −24]
//!   dB (reference §4 item 2: "from about −50 to −25 dB with most cases
//!   near-anechoic"); distension uniform in [1.05, 1.35] (reference row 21,
//!   ×1.18 with "wide overlap"; estimate of the spread).
//! - **Negatives**: 5 % carry chronic post-thrombotic change of the FV or
//!   PV (recanalized 0.2–0.8) and 5 % a GSV thrombophlebitis (estimates);
//!   the rest are normal legs.
//! - **Vignette**: age uniform 30–85 (De Maeseneer: median 62), Wells score
//!   uniform in 1–4 for positives and −1–1 for negatives (estimate).

use crate::case::{CaseFile, Diagnosis, TruthSpec, Vignette};
use crate::error::CaseError;
use echothigh_anatomy::{Anatomy, Patient, StructureId, ThrombusSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::HashMap;

/// Practice mode: about half the cases positive.
pub const PRACTICE: f64 = 0.5;
/// Realistic mode: 12 %, within the 10–15 % of suspected patients (reference row 32).
pub const REALISTIC: f64 = 0.12;
/// Presets and their probabilities (estimate).
pub const PRESETS: [(&str, f64); 3] = [
    ("lean-male", 0.35),
    ("average-female", 0.40),
    ("obese", 0.25),
];
/// Probability of a duplicated femoral vein (reference row 26).
pub const P_DUPLICATED: f64 = 0.197;
/// Probability of an inguinal lymph node (estimate).
pub const P_NODE: f64 = 0.10;
/// Probability of a tense leg (estimate).
pub const P_TENSE: f64 = 0.10;
/// Probability that an acute segment is non-occlusive (Markel: 18 % partial).
pub const P_PARTIAL: f64 = 0.18;
/// Probability that a near-anechoic echo is drawn for acute content.
pub const P_ANECHOIC: f64 = 0.75;

/// The pattern of a positive case and its probability (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Pattern {
    /// Popliteal vein only.
    Popliteal,
    /// Femoral vein only.
    Femoral,
    /// Common femoral vein only.
    CommonFemoral,
    /// Profunda only.
    Profunda,
    /// CFV and the proximal FV.
    Iliofemoral,
    /// Distal FV and the PV.
    Femoropopliteal,
}

/// Every pattern with its probability among positive cases (sums to 1).
pub const PATTERNS: [(Pattern, f64); 6] = [
    (Pattern::Popliteal, 0.203),
    (Pattern::Femoral, 0.076),
    (Pattern::CommonFemoral, 0.019),
    (Pattern::Profunda, 0.011),
    (Pattern::Iliofemoral, 0.362),
    (Pattern::Femoropopliteal, 0.329),
];

/// What one draw chose (for the frequency tests and the file's comment).
#[derive(Debug, Clone, PartialEq)]
pub struct Draw {
    /// The case file.
    pub file: CaseFile,
    /// The preset.
    pub preset: &'static str,
    /// The pattern when positive.
    pub pattern: Option<Pattern>,
}

/// The `s` range (m) of every tube of one patient.
type VeinRanges = HashMap<StructureId, (f64, f64)>;

/// Draws cases; caches one anatomy per (preset, duplicated) for the vein ranges.
pub struct Generator {
    rng: ChaCha8Rng,
    prevalence: f64,
    ranges: HashMap<(&'static str, bool), VeinRanges>,
    count: usize,
}

fn pick<T: Copy>(rng: &mut ChaCha8Rng, table: &[(T, f64)]) -> T {
    let mut u: f64 = rng.gen();
    for &(x, p) in table {
        if u < p {
            return x;
        }
        u -= p;
    }
    table[table.len() - 1].0
}

impl Generator {
    /// A generator of cases at `prevalence` (in [0, 1]) seeded by `seed`.
    pub fn new(prevalence: f64, seed: u64) -> Result<Generator, CaseError> {
        if !(prevalence.is_finite() && (0.0..=1.0).contains(&prevalence)) {
            return Err(CaseError::Generator {
                what: "--prevalence",
                value: prevalence,
                reason: "must be between 0 and 1 (practice 0.5, realistic 0.10-0.15)",
            });
        }
        Ok(Generator {
            rng: ChaCha8Rng::seed_from_u64(seed),
            prevalence,
            ranges: HashMap::new(),
            count: 0,
        })
    }

    fn range(&mut self, preset: &'static str, dup: bool, vein: StructureId) -> (f64, f64) {
        let map = self.ranges.entry((preset, dup)).or_insert_with(|| {
            let mut p = Patient::preset(preset).expect("built-in preset");
            p.duplicated_fv = dup;
            let a = Anatomy::new(p).expect("built-in preset builds");
            a.tubes().iter().map(|t| (t.id(), t.s_range())).collect()
        });
        map[&vein]
    }

    /// The next case.
    pub fn draw(&mut self) -> Draw {
        self.count += 1;
        let r = &mut self.rng;
        let preset = pick(r, &PRESETS);
        let dup = r.gen_bool(P_DUPLICATED);
        let node = r.gen_bool(P_NODE);
        let tense = r.gen_bool(P_TENSE);
        let positive = r.gen_bool(self.prevalence);
        let age = r.gen_range(30..=85);
        let mut segs = Vec::new();
        let mut pattern = None;
        let diagnosis;
        if positive {
            let pat = pick(r, &PATTERNS);
            pattern = Some(pat);
            self.positive(pat, preset, dup, &mut segs);
            diagnosis = Diagnosis::AcuteDvt;
        } else {
            let u: f64 = self.rng.gen();
            if u < 0.05 {
                let vein = if self.rng.gen_bool(0.5) {
                    StructureId::Fv
                } else {
                    StructureId::Pv
                };
                let mut s = self.isolated(preset, dup, vein, "chronic");
                s.recanalized = Some(round(self.rng.gen_range(0.2..0.8), 2));
                segs.push(s);
                diagnosis = Diagnosis::ChronicPostThrombotic;
            } else if u < 0.10 {
                let s = self.isolated(preset, dup, StructureId::Gsv, "acute_occlusive");
                let s = self.acute_content(s);
                segs.push(s);
                diagnosis = Diagnosis::SuperficialThrombophlebitis;
            } else {
                diagnosis = Diagnosis::Normal;
            }
        }
        let wells = if positive {
            self.rng.gen_range(1..=4)
        } else {
            self.rng.gen_range(-1..=1)
        };
        let mut patient = toml::Table::new();
        patient.insert("preset".into(), preset.into());
        patient.insert("duplicated_fv".into(), dup.into());
        patient.insert("lymph_node".into(), node.into());
        patient.insert("tense_muscle".into(), tense.into());
        let name = format!("generated-{:05}", self.count);
        Draw {
            file: CaseFile {
                title: format!("Generated case {} ({preset})", self.count),
                name,
                patient,
                vignette: Vignette {
                    age,
                    symptoms: "Unilateral leg pain and swelling (generated case)".into(),
                    wells,
                },
                thrombus: segs,
                truth: TruthSpec {
                    diagnosis,
                    teaching: None,
                },
                doppler: Default::default(),
            },
            preset,
            pattern,
        }
    }

    fn positive(
        &mut self,
        pat: Pattern,
        preset: &'static str,
        dup: bool,
        out: &mut Vec<ThrombusSpec>,
    ) {
        use StructureId::*;
        let whole = |g: &mut Self, v: StructureId| g.range(preset, dup, v);
        match pat {
            Pattern::Popliteal => out.push(self.isolated(preset, dup, Pv, "")),
            Pattern::CommonFemoral => out.push(self.isolated(preset, dup, Cfv, "")),
            Pattern::Profunda => out.push(self.isolated(preset, dup, Dfv, "")),
            Pattern::Femoral => {
                let vein = if dup && self.rng.gen_bool(0.5) {
                    Fv2
                } else {
                    Fv
                };
                out.push(self.isolated(preset, dup, vein, ""));
            }
            Pattern::Iliofemoral => {
                let (c0, c1) = whole(self, Cfv);
                let (f0, f1) = whole(self, Fv);
                let end = round(self.rng.gen_range(f0 + 0.03..f1), 3);
                out.push(self.segment(Cfv, round(c0 + 0.005, 3), c1, ""));
                out.push(self.segment(Fv, f0, end, "acute_occlusive"));
            }
            Pattern::Femoropopliteal => {
                let (f0, f1) = whole(self, Fv);
                let (p0, p1) = whole(self, Pv);
                let start = round(self.rng.gen_range(f0..f1 - 0.03), 3);
                let end = round(self.rng.gen_range(p0 + 0.03..p1 - 0.01), 3);
                out.push(self.segment(Fv, start, f1, ""));
                out.push(self.segment(Pv, p0, end, "acute_occlusive"));
            }
        }
        for s in out.iter_mut() {
            *s = self.acute_content(s.clone());
        }
    }

    /// A 3–8 cm segment placed uniformly on `vein` (clipped to it);
    /// `kind` empty draws occlusive / non-occlusive / free-floating.
    fn isolated(
        &mut self,
        preset: &'static str,
        dup: bool,
        vein: StructureId,
        kind: &str,
    ) -> ThrombusSpec {
        let (lo, hi) = self.range(preset, dup, vein);
        let len = self.rng.gen_range(0.03..0.08f64).min(hi - lo - 0.004);
        let start = round(self.rng.gen_range(lo + 0.002..hi - len - 0.001), 3);
        let end = ((start + len).min(hi) * 1e3).floor() / 1e3;
        self.segment(vein, start, end, kind)
    }

    fn segment(&mut self, vein: StructureId, s0: f64, s1: f64, kind: &str) -> ThrombusSpec {
        let kind = if kind.is_empty() {
            if self.rng.gen_bool(P_PARTIAL) {
                "acute_non_occlusive"
            } else if matches!(vein, StructureId::Cfv | StructureId::Fv)
                && s1 - s0 > 0.03
                && self.rng.gen_bool(0.10)
            {
                "free_floating"
            } else {
                "acute_occlusive"
            }
        } else {
            kind
        };
        let mut s = ThrombusSpec {
            vein: vein.as_str().into(),
            s_start: s0,
            s_end: s1,
            kind: kind.into(),
            fill: None,
            recanalized: None,
            tail: None,
            echo_db: None,
            distension: None,
            transition: None,
        };
        match kind {
            "acute_non_occlusive" => s.fill = Some(round(self.rng.gen_range(0.25..0.7), 2)),
            "free_floating" => {
                s.tail = Some(round(
                    self.rng.gen_range(0.01..(s1 - s0 - 0.01).min(0.03)),
                    3,
                ))
            }
            _ => {}
        }
        s
    }

    /// Draws the echo and distension of an acute segment (module docs).
    fn acute_content(&mut self, mut s: ThrombusSpec) -> ThrombusSpec {
        if s.kind == "chronic" {
            return s;
        }
        let echo = if self.rng.gen_bool(P_ANECHOIC) {
            self.rng.gen_range(-50.0..-38.0)
        } else {
            self.rng.gen_range(-38.0..-24.0)
        };
        s.echo_db = Some(round(echo, 1));
        if s.kind != "acute_non_occlusive" {
            s.distension = Some(round(self.rng.gen_range(1.05..1.35), 2));
        }
        s
    }
}

fn round(x: f64, digits: i32) -> f64 {
    let k = 10f64.powi(digits);
    (x * k).round() / k
}
