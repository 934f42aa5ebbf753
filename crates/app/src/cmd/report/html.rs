//! The report page: summary tables, the trend over sessions, and per case
//! its coverage strip with the truth, its force traces and its calls.

use super::{plots, Report};
use anyhow::Result;
use echothigh_exam::BinState;
use echothigh_records::stats::Rates;
use std::fmt::Write;

/// Escapes text for HTML. Five replacements: not worth a dependency.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// A fraction as a percentage with one decimal, or a dash when undefined.
pub fn pct(v: Option<f64>) -> String {
    v.map_or_else(|| "—".to_string(), |v| format!("{:.1} %", v * 100.0))
}

fn rates_cells(r: &Rates) -> String {
    format!(
        "<td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>",
        r.cases,
        pct(r.mean_coverage),
        pct(r.calls_correct),
        pct(r.pressure_adequacy),
        pct(r.sensitivity),
        pct(r.specificity)
    )
}

const RATE_HEAD: &str = "<th>cases scored</th><th>coverage</th><th>calls correct</th>\
    <th>pressure adequate</th><th>sensitivity</th><th>specificity</th>";

const STYLE: &str = "body{font-family:sans-serif;max-width:900px;margin:2em auto;color:#222}\
    table{border-collapse:collapse;margin:0.5em 0 1.5em}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}\
    th{background:#eee}td:first-child{text-align:left}.wrong{background:#fde0e0}.key span{display:inline-block;\
    width:1em;height:1em;vertical-align:middle;margin:0 4px 0 12px}section{border-top:2px solid #ccc;margin-top:2em}";

/// The whole page.
pub fn page(r: &Report) -> Result<String> {
    let h = &r.history;
    let mut o = String::new();
    let name = esc(&h.name);
    writeln!(
        o,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
    )?;
    writeln!(
        o,
        "<title>echothigh report: {name}</title><style>{STYLE}</style></head><body>"
    )?;
    writeln!(o, "<h1>Compression exam record: {name}</h1>")?;
    writeln!(
        o,
        "<p>Acute DVT is the positive finding. On a site with acute DVT an indeterminate \
         or missing call counts as a miss (false negative); on a site without, it is left out \
         of the specificity and counted as unresolved.</p>"
    )?;
    writeln!(o, "<h2>All sessions</h2><table id=\"overall\"><tr>{RATE_HEAD}<th>unresolved negatives</th></tr>")?;
    writeln!(
        o,
        "<tr>{}<td>{}</td></tr></table>",
        rates_cells(&h.rates),
        h.rates.confusion.unresolved_negative
    )?;

    writeln!(o, "<h2>Sessions</h2><table id=\"sessions\"><tr><th>session</th><th>protocol</th><th>host</th>{RATE_HEAD}</tr>")?;
    for (i, s) in h.sessions.iter().enumerate() {
        writeln!(
            o,
            "<tr><td>{}</td><td>{}</td><td>{}</td>{}</tr>",
            i + 1,
            esc(&s.protocol),
            esc(&s.host),
            rates_cells(&s.rates)
        )?;
    }
    writeln!(o, "</table>")?;
    writeln!(
        o,
        "<h3>Trend over sessions</h3>{}",
        plots::trend(&h.sessions)?
    )?;

    writeln!(o, "<h2>By site</h2><table id=\"sites\"><tr><th>site</th><th>TP</th><th>FN</th><th>TN</th><th>FP</th><th>unresolved</th><th>sensitivity</th><th>specificity</th></tr>")?;
    for s in &h.sites {
        let c = &s.confusion;
        writeln!(
            o,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&s.site),
            c.true_positive,
            c.false_negative,
            c.true_negative,
            c.false_positive,
            c.unresolved_negative,
            pct(s.sensitivity),
            pct(s.specificity)
        )?;
    }
    writeln!(o, "</table>")?;

    write!(o, "<h2>Cases</h2><p class=\"key\">Coverage:")?;
    for st in [
        BinState::Closed,
        BinState::NotClosed,
        BinState::InadequatePressure,
        BinState::NotExamined,
    ] {
        let c = plots::state_colour(st);
        write!(
            o,
            "<span style=\"background:rgb({},{},{})\"></span>{}",
            c.0,
            c.1,
            c.2,
            st.name().replace('_', " ")
        )?;
    }
    let (a, c) = (
        plots::truth_colour("acute_occlusive"),
        plots::truth_colour("chronic"),
    );
    writeln!(
        o,
        "<br>Truth (thin bar above):<span style=\"background:rgb({},{},{})\"></span>acute thrombus\
         <span style=\"background:rgb({},{},{})\"></span>chronic</p>",
        a.0, a.1, a.2, c.0, c.1, c.2
    )?;
    for d in &r.cases {
        writeln!(o, "<section><h3>{} (attempt {})</h3>", esc(&d.case), d.id)?;
        match &d.score {
            Some(s) => writeln!(
                o,
                "<p>Coverage {}, calls correct {}/{}, pressure adequate {}, peak force {:.1} N, \
                 mean force {:.1} N, excessive force on a free-floating tail {}×, time {:.0} s.</p>",
                pct(Some(s.coverage)),
                s.calls_correct,
                s.calls_total,
                pct(Some(s.pressure_adequate)),
                s.peak_force,
                s.mean_force,
                s.excessive_force_on_tail,
                s.duration
            )?,
            None => writeln!(o, "<p>Not finished (interrupted): no score.</p>")?,
        }
        writeln!(
            o,
            "<h4>Coverage and truth</h4>{}",
            plots::coverage_strip(&d.coverage, &d.truth)?
        )?;
        writeln!(
            o,
            "<h4>Force per compression ({} presses)</h4>{}",
            d.events.len(),
            plots::force_traces(&d.events)?
        )?;
        writeln!(o, "<h4>Calls</h4><table class=\"calls\"><tr><th>site</th><th>vein</th><th>s (cm)</th><th>call</th><th>truth</th><th>t (s)</th></tr>")?;
        for c in &d.calls {
            let class = if c.is_correct() {
                ""
            } else {
                " class=\"wrong\""
            };
            writeln!(
                o,
                "<tr{class}><td>{}</td><td>{}</td><td>{:.1}</td><td>{}</td><td>{}</td><td>{:.1}</td></tr>",
                esc(&c.site),
                esc(&c.vein),
                c.s * 100.0,
                c.finding.name(),
                c.truth.name(),
                c.t
            )?;
        }
        writeln!(o, "</table></section>")?;
    }
    writeln!(o, "</body></html>")?;
    Ok(o)
}
