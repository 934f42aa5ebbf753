//! The project's one CSV reader and writer (the `csv` crate), for the small
//! numeric tables users hand in: recorded probe trajectories (device
//! replay) and force–indentation curves (contact calibration).
//!
//! A table is a header line naming the columns (any order, matched without
//! regard to ASCII case; other columns are ignored), then one record a line.
//! Lines whose first character is `#` are comments; blank lines and the
//! spaces around fields are ignored; fields may be double-quoted.
//!
//! Every error names its line: 1-based, counting comment and blank lines,
//! as an editor shows it. The `csv` crate's own record line numbers skip
//! comment lines (an error on line 6 after a comment came out as line 5), so
//! lines are counted here from the byte offsets it reports.
//!
//! ```
//! let t = echothigh_table::Table::parse("# rig 2\nt,x\n\n0,1.5\n").unwrap();
//! let x = t.column("x").unwrap();
//! assert_eq!((t.rows()[0].line, t.rows()[0].number(x, "x").unwrap()), (4, 1.5));
//! ```
#![warn(missing_docs)]

use std::io::{Read, Write};

/// Why a table could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TableError {
    /// The input could not be read.
    #[error("cannot read the table: {0}")]
    Io(String),
    /// The input is larger than the caller's bound.
    #[error("the table is larger than {limit} bytes; refused")]
    TooLarge {
        /// The bound (bytes).
        limit: u64,
    },
    /// No header line (only comments and blank lines).
    #[error("no header line")]
    NoHeader,
    /// Malformed CSV (e.g. invalid UTF-8, an unterminated quote).
    #[error("line {line}: {message}")]
    Syntax {
        /// 1-based line number.
        line: u64,
        /// The CSV reader's message.
        message: String,
    },
    /// A required column is absent from the header.
    #[error("line {line}: missing column `{column}` (header has: {found})")]
    MissingColumn {
        /// Line of the header (1-based).
        line: u64,
        /// The required column.
        column: &'static str,
        /// The header as read.
        found: String,
    },
    /// A record has fewer fields than the header.
    #[error("line {line}: expected {expected} fields, found {found}")]
    ShortRow {
        /// 1-based line number.
        line: u64,
        /// Fields in the header.
        expected: usize,
        /// Fields in the record.
        found: usize,
    },
    /// A field that should hold a number does not.
    #[error("line {line}: column `{column}`: `{text}` is not a number")]
    NotANumber {
        /// 1-based line number.
        line: u64,
        /// Column name.
        column: &'static str,
        /// The field (at most 40 characters, with its length when cut).
        text: String,
    },
}

/// One record and the line it stands on.
#[derive(Debug, Clone)]
pub struct Row {
    /// 1-based line number, counting comment and blank lines.
    pub line: u64,
    fields: csv::StringRecord,
}

impl Row {
    /// The field of column `index` (from [`Table::column`]) as a number
    /// (which may be ±∞ or NaN if written so: callers check their ranges);
    /// `name` is the column's name for the error.
    pub fn number(&self, index: usize, name: &'static str) -> Result<f64, TableError> {
        let text = self.fields.get(index).unwrap_or("");
        text.parse().map_err(|_| TableError::NotANumber {
            line: self.line,
            column: name,
            text: excerpt(text),
        })
    }
}

/// A parsed table: its header and its records.
#[derive(Debug, Clone)]
pub struct Table {
    header_line: u64,
    header: Vec<String>,
    rows: Vec<Row>,
}

/// At most 40 characters of a field for an error message, with its length
/// when cut (a 50 MB "number" must not be echoed whole).
fn excerpt(text: &str) -> String {
    const KEEP: usize = 40;
    match text.char_indices().nth(KEEP) {
        None => text.to_string(),
        Some((cut, _)) => format!("{}… ({} bytes)", &text[..cut], text.len()),
    }
}

/// Finds the line of each record from the byte offset the `csv` crate
/// reports, which is where the previous record ended: the comment and empty
/// lines it skipped come first. Offsets only grow, so all calls together
/// read the input once.
struct LineCounter<'a> {
    text: &'a [u8],
    offset: usize,
    line: u64,
}

impl LineCounter<'_> {
    /// The 1-based line of the record whose skipped prefix starts at byte
    /// `offset` (not before the previous call's).
    fn line_at(&mut self, offset: u64) -> u64 {
        let mut start = (offset as usize).clamp(self.offset, self.text.len());
        // Skip the lines the reader skipped: empty ones and `#` comments.
        loop {
            let rest = &self.text[start..];
            let eol = rest.iter().position(|&b| b == b'\n');
            let line = &rest[..eol.unwrap_or(rest.len())];
            let skipped = line.is_empty() || line == b"\r" || line.first() == Some(&b'#');
            match eol {
                Some(n) if skipped => start += n + 1,
                _ => break,
            }
        }
        self.line += self.text[self.offset..start]
            .iter()
            .filter(|&&b| b == b'\n')
            .count() as u64;
        self.offset = start;
        self.line
    }
}

impl Table {
    /// Reads a table from `reader`, refusing input beyond `max_bytes`.
    pub fn read(reader: impl Read, max_bytes: u64) -> Result<Self, TableError> {
        let mut text = Vec::new();
        reader
            .take(max_bytes.saturating_add(1))
            .read_to_end(&mut text)
            .map_err(|e| TableError::Io(e.to_string()))?;
        if text.len() as u64 > max_bytes {
            return Err(TableError::TooLarge { limit: max_bytes });
        }
        Self::parse_bytes(&text)
    }

    /// Parses a table held in memory.
    pub fn parse(text: &str) -> Result<Self, TableError> {
        Self::parse_bytes(text.as_bytes())
    }

    fn parse_bytes(text: &[u8]) -> Result<Self, TableError> {
        let mut lines = LineCounter {
            text,
            offset: 0,
            line: 1,
        };
        let mut csv = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(text);
        let mut header: Option<(u64, Vec<String>)> = None;
        let mut rows = Vec::new();
        let mut record = csv::StringRecord::new();
        loop {
            let more = csv
                .read_record(&mut record)
                .map_err(|e| TableError::Syntax {
                    line: e.position().map_or(0, |p| lines.line_at(p.byte())),
                    message: e.to_string(),
                })?;
            if !more {
                break;
            }
            let line = record.position().map_or(0, |p| lines.line_at(p.byte()));
            match &header {
                None => header = Some((line, record.iter().map(str::to_string).collect())),
                Some((_, names)) if record.len() < names.len() => {
                    return Err(TableError::ShortRow {
                        line,
                        expected: names.len(),
                        found: record.len(),
                    })
                }
                Some(_) => rows.push(Row {
                    line,
                    fields: record.clone(),
                }),
            }
        }
        let (header_line, header) = header.ok_or(TableError::NoHeader)?;
        Ok(Table {
            header_line,
            header,
            rows,
        })
    }

    /// The index of column `name` (ASCII case ignored).
    pub fn column(&self, name: &'static str) -> Result<usize, TableError> {
        self.header
            .iter()
            .position(|h| h.eq_ignore_ascii_case(name))
            .ok_or_else(|| TableError::MissingColumn {
                line: self.header_line,
                column: name,
                found: self.header.join(","),
            })
    }

    /// The records, in order.
    pub fn rows(&self) -> &[Row] {
        &self.rows
    }
}

/// The project's one CSV writer (the `csv` crate): records streamed to
/// `out` one at a time, every field as the caller formatted it (callers
/// choose their numbers' precision). I/O errors come back as `io::Error`,
/// for the caller to name its file.
pub struct RowWriter<W: Write> {
    inner: csv::Writer<W>,
}

impl<W: Write> RowWriter<W> {
    /// A writer of records into `out` (no header is added: write it as the
    /// first record).
    pub fn new(out: W) -> Self {
        RowWriter {
            inner: csv::WriterBuilder::new()
                .has_headers(false)
                .from_writer(out),
        }
    }

    /// Writes one record.
    pub fn record<F: AsRef<[u8]>>(
        &mut self,
        fields: impl IntoIterator<Item = F>,
    ) -> std::io::Result<()> {
        self.inner.write_record(fields).map_err(into_io)
    }

    /// Hands everything written so far to `out` and flushes it.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

fn into_io(e: csv::Error) -> std::io::Error {
    match e.into_kind() {
        csv::ErrorKind::Io(e) => e,
        other => std::io::Error::other(format!("{other:?}")),
    }
}

/// Writes a table: `comment` lines first (each prefixed `# `), the header,
/// then the rows (each field as given: callers format their numbers).
pub fn write<W: Write, R, F>(
    out: W,
    comment: &str,
    header: &[&str],
    rows: impl IntoIterator<Item = R>,
) -> std::io::Result<()>
where
    R: IntoIterator<Item = F>,
    F: AsRef<[u8]>,
{
    let mut out = out;
    for line in comment.lines() {
        writeln!(out, "# {line}")?;
    }
    let mut w = RowWriter::new(out);
    w.record(header)?;
    for row in rows {
        w.record(row)?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The issue's case: an error on line 6, after a comment and a blank
    /// line, says line 6 (the csv crate's own count said 5).
    #[test]
    fn error_after_a_comment_and_a_blank_line_names_its_line() {
        let text = "# recorded 2026-11-24\nt,x\n0,0\n\n1,1\n2,oops\n";
        let t = Table::parse(text).unwrap();
        let x = t.column("x").unwrap();
        let lines: Vec<u64> = t.rows().iter().map(|r| r.line).collect();
        assert_eq!(lines, [3, 5, 6]);
        assert_eq!(
            t.rows()[2].number(x, "x").unwrap_err(),
            TableError::NotANumber {
                line: 6,
                column: "x",
                text: "oops".into()
            }
        );
    }

    #[test]
    fn header_after_comments_names_its_line_when_a_column_is_missing() {
        let t = Table::parse("# a\n\n# b\nT, y\n0,1\n").unwrap();
        assert_eq!(t.column("t").unwrap(), 0);
        assert_eq!(
            t.column("z").unwrap_err(),
            TableError::MissingColumn {
                line: 4,
                column: "z",
                found: "T,y".into()
            }
        );
    }

    #[test]
    fn short_rows_quotes_and_crlf() {
        let t = Table::parse("a,b\r\n\"1\",\" 2 \"\r\n# c\r\n3,4\r\n").unwrap();
        let rows: Vec<(u64, f64, f64)> = t
            .rows()
            .iter()
            .map(|r| (r.line, r.number(0, "a").unwrap(), r.number(1, "b").unwrap()))
            .collect();
        assert_eq!(rows, [(2, 1.0, 2.0), (4, 3.0, 4.0)]);
        let e = Table::parse("a,b\n1,2\n\n3\n").unwrap_err();
        assert_eq!(
            e,
            TableError::ShortRow {
                line: 4,
                expected: 2,
                found: 1
            }
        );
        assert_eq!(
            Table::parse("# only\n\n").unwrap_err(),
            TableError::NoHeader
        );
        assert!(matches!(
            Table::read(&b"a\n1\n2\n"[..], 4),
            Err(TableError::TooLarge { limit: 4 })
        ));
    }

    #[test]
    fn long_fields_are_cut_in_errors() {
        let junk = "9".repeat(30) + &"x".repeat(100);
        let t = Table::parse(&format!("a\n{junk}\n")).unwrap();
        let TableError::NotANumber { text, .. } = t.rows()[0].number(0, "a").unwrap_err() else {
            panic!("not NotANumber")
        };
        assert!(text.ends_with("… (130 bytes)"), "{text}");
    }

    #[test]
    fn written_tables_read_back() {
        let mut out = Vec::new();
        let rows = [["0.000", "0.00000"], ["1.500", "0.47000"]];
        write(
            &mut out,
            "calibrated\nrig 2",
            &["depth_mm", "force_n"],
            rows,
        )
        .unwrap();
        let text = String::from_utf8(out).unwrap();
        assert_eq!(
            text,
            "# calibrated\n# rig 2\ndepth_mm,force_n\n0.000,0.00000\n1.500,0.47000\n"
        );
        let t = Table::parse(&text).unwrap();
        let f = t.column("force_n").unwrap();
        assert_eq!(
            (t.rows()[1].line, t.rows()[1].number(f, "force_n").unwrap()),
            (5, 0.47)
        );
    }
}
