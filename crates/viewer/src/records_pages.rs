//! The read-only record pages (issue 14): `/records`, the instructor's
//! table of every trainee (sortable by a click on a column's heading), and
//! `/records/{name}`, a trainee's history (sessions, cases, scores, rates
//! per site). Rendered on the server from `echothigh-records`; they change
//! nothing.

use echothigh_records::stats::Rates;
use echothigh_records::{TraineeHistory, TraineeSummary};
use std::fmt::Write;

/// `text` with the HTML specials escaped.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A rate in [0, 1] as a percentage, `–` without data.
fn pct(v: Option<f64>) -> String {
    v.map_or_else(|| "–".into(), |v| format!("{:.0} %", 100.0 * v))
}

/// Unix milliseconds as `YYYY-MM-DD HH:MM` (UTC), `–` for none.
fn when(ms: Option<i64>) -> String {
    let Some(ms) = ms else { return "–".into() };
    let secs = ms.div_euclid(1000);
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm:
    // no date crate is needed for one format).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}",
        rem / 3600,
        rem % 3600 / 60
    )
}

const HEAD: &str = r#"<!doctype html><html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>body{font:14px system-ui,sans-serif;margin:20px;background:#14181f;color:#e6e9ee}
a{color:#7fb2ff}table{border-collapse:collapse;margin:8px 0 18px}th,td{padding:3px 10px;text-align:left;
border-bottom:1px solid #2a313d}th{color:#8d96a5;font-weight:normal}th.sort{cursor:pointer}
td.n{text-align:right;font-variant-numeric:tabular-nums}.dim{color:#8d96a5}</style>
<script>function sortBy(th){const t=th.closest('table'),i=[...th.parentNode.children].indexOf(th),
d=th.dataset.dir==='a'?'d':'a';th.dataset.dir=d;const rows=[...t.tBodies[0].rows];
rows.sort((a,b)=>{const x=a.cells[i].dataset.v??a.cells[i].textContent,y=b.cells[i].dataset.v??b.cells[i].textContent;
const nx=parseFloat(x),ny=parseFloat(y);const c=isNaN(nx)||isNaN(ny)?x.localeCompare(y):nx-ny;return d==='a'?c:-c});
rows.forEach(r=>t.tBodies[0].append(r))}</script>"#;

/// A sortable numeric cell: the shown text, the value it sorts by.
fn num(shown: String, v: Option<f64>) -> String {
    format!(
        r#"<td class="n" data-v="{}">{shown}</td>"#,
        v.map_or(-1.0, |v| v)
    )
}

/// The rate cells shared by both pages.
fn rate_cells(r: &Rates) -> String {
    [
        num(r.cases.to_string(), Some(f64::from(r.cases))),
        num(pct(r.mean_coverage), r.mean_coverage),
        num(pct(r.calls_correct), r.calls_correct),
        num(pct(r.pressure_adequacy), r.pressure_adequacy),
        num(pct(r.sensitivity), r.sensitivity),
        num(pct(r.specificity), r.specificity),
    ]
    .concat()
}

const RATE_HEADS: &str = "<th class=sort onclick=sortBy(this)>cases finished</th>\
<th class=sort onclick=sortBy(this)>coverage</th><th class=sort onclick=sortBy(this)>calls right</th>\
<th class=sort onclick=sortBy(this)>adequate pressure</th><th class=sort onclick=sortBy(this)>sensitivity</th>\
<th class=sort onclick=sortBy(this)>specificity</th>";

/// The instructor's page: every trainee, with the rates over their
/// finished cases (sensitivity and specificity for acute DVT).
pub fn instructor(trainees: &[TraineeSummary], db: &str) -> String {
    let mut h = String::from(HEAD);
    let _ = write!(
        h,
        "<title>echothigh — trainees</title></head><body><h1>Trainees</h1>\
         <p class=dim>Read-only, from {}. Click a heading to sort.</p>\
         <table id=trainees><thead><tr><th class=sort onclick=sortBy(this)>trainee</th>\
         <th class=sort onclick=sortBy(this)>sessions</th><th class=sort onclick=sortBy(this)>last seen (UTC)</th>{RATE_HEADS}</tr></thead><tbody>",
        escape(db)
    );
    for t in trainees {
        let _ = write!(
            h,
            r#"<tr><td><a href="/records/{}">{}</a></td>{}<td data-v="{}">{}</td>{}</tr>"#,
            escape(&percent_encode(&t.name)),
            escape(&t.name),
            num(t.sessions.to_string(), Some(f64::from(t.sessions))),
            t.last_seen_ms.unwrap_or(0),
            when(t.last_seen_ms),
            rate_cells(&t.rates)
        );
    }
    h.push_str("</tbody></table></body></html>");
    h
}

/// A trainee's page: the rates, per site, and each session's cases.
pub fn trainee(t: &TraineeHistory, db: &str) -> String {
    let mut h = String::from(HEAD);
    let name = escape(&t.name);
    let _ = write!(
        h,
        "<title>echothigh — {name}</title></head><body><p><a href=\"/records\">all trainees</a></p>\
         <h1>{name}</h1><p class=dim>Read-only, from {}.</p><table id=rates><thead><tr>{RATE_HEADS}</tr></thead>\
         <tbody><tr>{}</tr></tbody></table><h2>By site (acute DVT)</h2><table id=sites><thead><tr>\
         <th class=sort onclick=sortBy(this)>site</th><th>TP</th><th>FN</th><th>TN</th><th>FP</th>\
         <th class=sort onclick=sortBy(this)>sensitivity</th><th class=sort onclick=sortBy(this)>specificity</th></tr></thead><tbody>",
        escape(db),
        rate_cells(&t.rates)
    );
    for s in &t.sites {
        let c = &s.confusion;
        let _ = write!(
            h,
            "<tr><td>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td>{}{}</tr>",
            escape(&s.site),
            c.true_positive,
            c.false_negative,
            c.true_negative,
            c.false_positive,
            num(pct(s.sensitivity), s.sensitivity),
            num(pct(s.specificity), s.specificity)
        );
    }
    h.push_str("</tbody></table>");
    breakdown(&mut h, t);
    h.push_str("<h2>Sessions</h2>");
    for s in t.sessions.iter().rev() {
        let _ = write!(
            h,
            "<h3>{} · {} · {}</h3><table class=cases><thead><tr><th>case</th><th>finished</th>\
             <th>calls right</th><th>coverage</th><th>adequate pressure</th><th>peak force</th></tr></thead><tbody>",
            when(Some(s.started_ms)),
            escape(&s.protocol),
            escape(&s.host)
        );
        for c in &s.cases {
            let score = c.score.as_ref();
            let _ = write!(
                h,
                "<tr><td>{}</td><td>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td></tr>",
                escape(&c.case),
                if c.finished_ms.is_some() { when(c.finished_ms) } else { "unfinished".into() },
                score.map_or("–".into(), |s| format!("{} / {}", s.calls_correct, s.calls_total)),
                pct(score.map(|s| s.coverage)),
                pct(score.map(|s| s.pressure_adequate)),
                score.map_or("–".into(), |s| format!("{:.1} N", s.peak_force)),
            );
        }
        h.push_str("</tbody></table>");
    }
    h.push_str("</body></html>");
    h
}

/// The per-site breakdown beyond the acute-DVT counts: the Doppler
/// calls' accuracy per site and the segments the finished cases missed.
fn breakdown(h: &mut String, t: &TraineeHistory) {
    h.push_str(
        "<h2>Doppler calls by site</h2><table id=doppler><thead><tr><th>site</th><th>right</th>\
         <th>sites</th><th>called</th><th>pattern right</th><th>augmentation right</th>\
         <th>accuracy</th></tr></thead><tbody>",
    );
    for d in &t.doppler {
        let _ = write!(
            h,
            "<tr><td>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td>\
             <td class=n>{}</td>{}</tr>",
            escape(&d.site),
            d.correct,
            d.total,
            d.called,
            d.flow_correct,
            d.augments_correct,
            num(pct(d.accuracy()), d.accuracy())
        );
    }
    h.push_str("</tbody></table><h2>Missed segments</h2>");
    if t.missed.is_empty() {
        h.push_str(
            "<p id=missed class=dim>None: every diseased segment was examined or called.</p>",
        );
        return;
    }
    h.push_str(
        "<table id=missed><thead><tr><th>case</th><th>vein</th><th>from (mm)</th><th>to (mm)</th>\
         <th>truth</th></tr></thead><tbody>",
    );
    for m in &t.missed {
        let s = &m.segment;
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td class=n>{:.0}</td><td class=n>{:.0}</td><td>{}</td></tr>",
            escape(&m.case),
            escape(&s.vein),
            s.s_start * 1e3,
            s.s_end * 1e3,
            s.truth.name()
        );
    }
    h.push_str("</tbody></table>");
}

/// `name` percent-encoded for a URL path segment (RFC 3986 unreserved
/// characters kept).
pub fn percent_encode(name: &str) -> String {
    let mut out = String::new();
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_escaping_and_encoding() {
        // 2026-11-25 09:58 UTC = 1 795 600 680 s (date -d @1795600680 -u).
        assert_eq!(when(Some(1_795_600_680_000)), "2026-11-25 09:58");
        assert_eq!(when(Some(0)), "1970-01-01 00:00");
        // 2000-02-29 12:00 UTC, a leap day of a century year divisible by 400.
        assert_eq!(when(Some(951_825_600_000)), "2000-02-29 12:00");
        assert_eq!(
            escape("<b>\"Ada\" & 'Bo'</b>"),
            "&lt;b&gt;&quot;Ada&quot; &amp; &#39;Bo&#39;&lt;/b&gt;"
        );
        assert_eq!(percent_encode("Ada Lovelace/é"), "Ada%20Lovelace%2F%C3%A9");
    }

    /// The trainee page shows the per-site counts, sensitivity and
    /// specificity, the Doppler accuracy and the missed segments it is
    /// given (the numbers of `crates/records/tests/suite/breakdown.rs`: cfv 1 of
    /// 3 Doppler calls right = 33 %, popliteal 2 of 3 = 67 %; per-site
    /// TP 1 FN 1 TN 0 FP 1 → sensitivity 50 %, specificity 0 %).
    #[test]
    fn trainee_page_renders_the_breakdown() {
        use echothigh_exam::{Finding, MissedSegment};
        use echothigh_records::breakdown::{DopplerAccuracy, MissedInCase};
        use echothigh_records::stats::Confusion;
        use echothigh_records::SiteStats;
        let confusion = Confusion {
            true_positive: 1,
            false_negative: 1,
            true_negative: 0,
            false_positive: 1,
            unresolved_negative: 1,
        };
        let h = TraineeHistory {
            name: "Ines".into(),
            sessions: Vec::new(),
            rates: Rates::default(),
            sites: vec![SiteStats {
                site: "cfv".into(),
                sensitivity: confusion.sensitivity(),
                specificity: confusion.specificity(),
                confusion,
            }],
            missed: vec![MissedInCase {
                case_id: 2,
                case: "B".into(),
                segment: MissedSegment {
                    vein: "fv".into(),
                    s_start: 0.17,
                    s_end: 0.23,
                    truth: Finding::AcuteDvt,
                },
            }],
            doppler: vec![
                DopplerAccuracy {
                    site: "cfv".into(),
                    total: 3,
                    called: 2,
                    correct: 1,
                    flow_correct: 1,
                    augments_correct: 2,
                },
                DopplerAccuracy {
                    site: "popliteal".into(),
                    total: 3,
                    called: 3,
                    correct: 2,
                    flow_correct: 3,
                    augments_correct: 2,
                },
            ],
        };
        let page = trainee(&h, "test.sqlite3");
        let n = |v: &str| format!("<td class=n>{v}</td>");
        let sites = &page[page.find("id=sites").unwrap()..page.find("id=doppler").unwrap()];
        assert!(
            sites.contains(&format!(
                "<td>cfv</td>{}{}{}{}",
                n("1"),
                n("1"),
                n("0"),
                n("1")
            )),
            "{sites}"
        );
        assert!(
            sites.contains(">50 %<") && sites.contains(">0 %<"),
            "{sites}"
        );
        let doppler = &page[page.find("id=doppler").unwrap()..page.find("id=missed").unwrap()];
        assert!(
            doppler.contains(&format!(
                "<td>cfv</td>{}{}{}{}{}",
                n("1"),
                n("3"),
                n("2"),
                n("1"),
                n("2")
            )),
            "{doppler}"
        );
        assert!(
            doppler.contains(">33 %<") && doppler.contains(">67 %<"),
            "{doppler}"
        );
        let missed = &page[page.find("id=missed").unwrap()..];
        assert!(
            missed.contains(&format!(
                "<td>B</td><td>fv</td>{}{}<td>acute_dvt</td>",
                n("170"),
                n("230")
            )),
            "{missed}"
        );
    }
}
