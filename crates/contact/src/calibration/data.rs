//! Force–indentation data: the CSV format the calibration reads.
//!
//! ```text
//! # comment lines start with '#'
//! depth_mm,force_n
//! 0.0,0.0
//! 1.0,0.47
//! ```
//!
//! Required columns (by header name, case-insensitive, any order; other
//! columns are ignored): `depth_mm`, the probe's displacement from first
//! contact (mm, ≥ 0, strictly increasing), and `force_n`, the normal force on
//! the probe (N, ≥ 0). Every error names its line (1-based, counting comment
//! and blank lines). Read and written with the project's one CSV reader and
//! writer, [`echothigh_table`].

use crate::error::CsvError;
use echothigh_table::Table;
use std::io::Read;
use std::path::Path;

/// A force–indentation curve, in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct IndentationCurve {
    /// Indentation depths from first contact, m, strictly increasing.
    pub depth: Vec<f64>,
    /// Normal force on the probe at each depth, N.
    pub force: Vec<f64>,
}

/// Minimum number of data rows accepted.
pub const MIN_ROWS: usize = 3;

/// Largest accepted calibration file (bytes): a force–indentation curve
/// has tens to thousands of rows of ~20 bytes.
pub const MAX_CSV_BYTES: u64 = 1 << 20;

impl IndentationCurve {
    /// Parses the CSV text described in the module docs.
    pub fn from_csv_str(text: &str) -> Result<Self, CsvError> {
        Self::from_reader(text.as_bytes())
    }

    /// Reads and parses a CSV file.
    pub fn from_path(path: &Path) -> Result<Self, CsvError> {
        let f = std::fs::File::open(path)
            .map_err(|e| CsvError::Io(format!("{}: {e}", path.display())))?;
        Self::from_reader(f)
    }

    /// Parses CSV from any reader (the project's one reader,
    /// [`echothigh_table`]). Input beyond [`MAX_CSV_BYTES`] is refused.
    pub fn from_reader(r: impl Read) -> Result<Self, CsvError> {
        let table = Table::read(r, MAX_CSV_BYTES)?;
        let i_depth = table.column("depth_mm")?;
        let i_force = table.column("force_n")?;
        let mut depth = Vec::with_capacity(table.rows().len());
        let mut force = Vec::with_capacity(table.rows().len());
        for row in table.rows() {
            let line = row.line;
            let num = |i: usize, column: &'static str| -> Result<f64, CsvError> {
                match row.number(i, column)? {
                    v if v.is_finite() => Ok(v),
                    value => Err(CsvError::NotFinite {
                        line,
                        column,
                        value,
                    }),
                }
            };
            let d = num(i_depth, "depth_mm")?;
            let f = num(i_force, "force_n")?;
            for (column, value) in [("depth_mm", d), ("force_n", f)] {
                if value < 0.0 {
                    return Err(CsvError::Negative {
                        line,
                        column,
                        value,
                    });
                }
            }
            if let Some(&prev) = depth.last() {
                let prev_mm: f64 = prev * 1e3;
                if d <= prev_mm {
                    return Err(CsvError::NonMonotonicDepth {
                        line,
                        depth_mm: d,
                        previous_mm: prev_mm,
                    });
                }
            }
            depth.push(d * 1e-3);
            force.push(f);
        }
        if depth.len() < MIN_ROWS {
            return Err(CsvError::TooFewRows {
                found: depth.len(),
                required: MIN_ROWS,
            });
        }
        Ok(Self { depth, force })
    }

    /// Writes the curve as CSV text (`depth_mm,force_n`), with `comment`
    /// lines first (each prefixed by `# `).
    pub fn to_csv_string(&self, comment: &str) -> String {
        let rows = self
            .depth
            .iter()
            .zip(&self.force)
            .map(|(d, f)| [format!("{:.3}", d * 1e3), format!("{f:.5}")]);
        let mut out = Vec::new();
        echothigh_table::write(&mut out, comment, &["depth_mm", "force_n"], rows)
            .expect("writing to memory cannot fail");
        String::from_utf8(out).expect("the fields are ASCII numbers")
    }

    /// Linear interpolation of the force at depth `d` (m), clamped to the
    /// curve's range.
    pub fn force_at(&self, d: f64) -> f64 {
        interpolate(&self.depth, &self.force, d)
    }
}

/// Piecewise-linear interpolation of `(xs, ys)` at `x`, `xs` increasing,
/// clamped at both ends.
pub fn interpolate(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    match xs.len() {
        0 => 0.0,
        1 => ys[0],
        n => {
            if x <= xs[0] {
                return ys[0];
            }
            if x >= xs[n - 1] {
                return ys[n - 1];
            }
            let k = xs.partition_point(|&v| v <= x).clamp(1, n - 1);
            let t = (x - xs[k - 1]) / (xs[k] - xs[k - 1]);
            ys[k - 1] + t * (ys[k] - ys[k - 1])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use echothigh_table::TableError;

    #[test]
    fn parses_with_comments_any_order_and_extra_columns() {
        let c = IndentationCurve::from_csv_str(
            "# source\n# more\nforce_N, note ,Depth_mm\n0,a,0\n0.5,b,1.0\n1.2,c,2\n",
        )
        .unwrap();
        assert_eq!(c.depth, vec![0.0, 0.001, 0.002]);
        assert_eq!(c.force, vec![0.0, 0.5, 1.2]);
        assert!((c.force_at(0.0015) - 0.85).abs() < 1e-12);
    }

    #[test]
    fn missing_column_names_header_line() {
        let e =
            IndentationCurve::from_csv_str("# c\ndepth_mm,newtons\n0,0\n1,1\n2,2\n").unwrap_err();
        assert!(
            matches!(
                e,
                CsvError::Table(TableError::MissingColumn {
                    line: 2,
                    column: "force_n",
                    ..
                })
            ),
            "{e:?}"
        );
        assert!(e
            .to_string()
            .starts_with("line 2: missing column `force_n`"));
    }

    #[test]
    fn non_numeric_names_its_line() {
        let e =
            IndentationCurve::from_csv_str("depth_mm,force_n\n0,0\n# c\n1,abc\n2,2\n").unwrap_err();
        assert_eq!(
            e,
            CsvError::Table(TableError::NotANumber {
                line: 4,
                column: "force_n",
                text: "abc".into()
            })
        );
        let e = IndentationCurve::from_csv_str("depth_mm,force_n\n0,0\n1,NaN\n").unwrap_err();
        assert!(matches!(e, CsvError::NotFinite { line: 3, .. }), "{e:?}");
    }

    #[test]
    fn non_monotonic_depth_names_its_line() {
        let e =
            IndentationCurve::from_csv_str("depth_mm,force_n\n0,0\n2,1\n1.5,2\n3,3\n").unwrap_err();
        assert_eq!(
            e,
            CsvError::NonMonotonicDepth {
                line: 4,
                depth_mm: 1.5,
                previous_mm: 2.0
            }
        );
        assert!(e.to_string().contains("line 4"));
    }

    #[test]
    fn short_rows_negative_values_and_too_few_rows() {
        let e = IndentationCurve::from_csv_str("depth_mm,force_n\n0,0\n1\n").unwrap_err();
        assert!(
            matches!(e, CsvError::Table(TableError::ShortRow { line: 3, .. })),
            "{e:?}"
        );
        let e = IndentationCurve::from_csv_str("depth_mm,force_n\n0,-1\n").unwrap_err();
        assert!(matches!(
            e,
            CsvError::Negative {
                line: 2,
                column: "force_n",
                ..
            }
        ));
        let e = IndentationCurve::from_csv_str("depth_mm,force_n\n0,0\n1,1\n").unwrap_err();
        assert!(matches!(e, CsvError::TooFewRows { found: 2, .. }));
    }

    #[test]
    fn csv_round_trip() {
        let c = IndentationCurve {
            depth: vec![0.0, 0.001, 0.0025],
            force: vec![0.0, 0.4, 1.25],
        };
        let back = IndentationCurve::from_csv_str(&c.to_csv_string("x\ny")).unwrap();
        assert_eq!(back, c);
    }
}
