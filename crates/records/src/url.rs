//! The database URL: `sqlite://PATH` or `postgres://…`, and the default
//! SQLite file under the user's data directory.

use crate::RecordsError;
use std::path::{Path, PathBuf};

/// Which database server speaks behind a URL.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// A SQLite file.
    Sqlite,
    /// A PostgreSQL server.
    Postgres,
}

/// A parsed database URL.
#[derive(Debug, Clone)]
pub struct DbUrl {
    /// The backend.
    pub backend: Backend,
    /// The URL handed to the driver.
    pub(crate) connect: String,
    /// The URL as shown in messages (password hidden).
    pub shown: String,
    /// The SQLite file (SQLite only).
    pub path: Option<PathBuf>,
}

/// The default records file: `data_dir()/echothigh/records.sqlite3`
/// (`~/.local/share/echothigh/records.sqlite3` on Linux).
pub fn default_path() -> Result<PathBuf, RecordsError> {
    let dir = dirs::data_dir().ok_or(RecordsError::NoDataDir)?;
    Ok(dir.join("echothigh").join("records.sqlite3"))
}

/// The URL of the SQLite file at `path`.
pub fn sqlite_url(path: &Path) -> String {
    format!("sqlite://{}", path.display())
}

impl DbUrl {
    /// Parses `url`; `None` is the default SQLite file.
    pub fn parse(url: Option<&str>) -> Result<DbUrl, RecordsError> {
        let url = match url {
            Some(u) => u.to_string(),
            None => sqlite_url(&default_path()?),
        };
        if let Some(rest) = url
            .strip_prefix("sqlite://")
            .or_else(|| url.strip_prefix("sqlite:"))
        {
            // The driver reads `?…` as options; a path with `?` or `#` would
            // be cut there, so it is refused rather than silently renamed.
            if rest.is_empty() || rest.contains(['?', '#']) {
                return Err(RecordsError::BadScheme { url });
            }
            let path = PathBuf::from(rest);
            return Ok(DbUrl {
                backend: Backend::Sqlite,
                // `mode=rwc`: read-write, created when missing.
                connect: format!("sqlite://{rest}?mode=rwc"),
                shown: path.display().to_string(),
                path: Some(path),
            });
        }
        if url.starts_with("postgres://") || url.starts_with("postgresql://") {
            let shown = match url::Url::parse(&url) {
                Ok(mut u) => {
                    if u.password().is_some() {
                        let _ = u.set_password(Some("***"));
                    }
                    u.to_string()
                }
                Err(_) => {
                    return Err(RecordsError::BadScheme {
                        url: hide_all(&url),
                    })
                }
            };
            return Ok(DbUrl {
                backend: Backend::Postgres,
                connect: url,
                shown,
                path: None,
            });
        }
        Err(RecordsError::BadScheme {
            url: hide_all(&url),
        })
    }
}

/// An unparseable URL shown without anything between `://` and `@` (where
/// a password would be).
fn hide_all(url: &str) -> String {
    match (url.find("://"), url.rfind('@')) {
        (Some(a), Some(b)) if b > a => format!("{}://***{}", &url[..a], &url[b..]),
        _ => url.to_string(),
    }
}

/// Checks a SQLite file before the driver opens it, so that a read-only or
/// foreign file is named in a clear error rather than a driver code: the
/// parent directories are created, the directory and an existing file must
/// be writable (by their permission bits: root ignores them, SQLite would
/// not refuse), and an existing non-empty file must start with SQLite's
/// 16-byte header (`SQLite format 3\0`, sqlite.org/fileformat.html §1.3).
pub(crate) fn check_sqlite_file(path: &Path) -> Result<(), RecordsError> {
    use std::io::Read;
    let shown = path.display().to_string();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| io_error(&dir, e))?;
    let dir_meta = std::fs::metadata(&dir).map_err(|e| io_error(&dir, e))?;
    if dir_meta.permissions().readonly() {
        return Err(RecordsError::ReadOnly {
            path: dir.display().to_string(),
            why: "the directory is not writable; SQLite keeps its journal beside the file".into(),
        });
    }
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(io_error(path, e)),
    };
    if !meta.is_file() {
        return Err(RecordsError::NotADatabase { path: shown });
    }
    if meta.permissions().readonly() {
        return Err(RecordsError::ReadOnly {
            path: shown,
            why: "the file is not writable".into(),
        });
    }
    let mut head = Vec::with_capacity(16);
    std::fs::File::open(path)
        .and_then(|f| f.take(16).read_to_end(&mut head))
        .map_err(|e| io_error(path, e))?;
    if !head.is_empty() && head != b"SQLite format 3\0" {
        return Err(RecordsError::NotADatabase { path: shown });
    }
    Ok(())
}

fn io_error(path: &Path, source: std::io::Error) -> RecordsError {
    if source.kind() == std::io::ErrorKind::PermissionDenied {
        return RecordsError::ReadOnly {
            path: path.display().to_string(),
            why: source.to_string(),
        };
    }
    RecordsError::Io {
        path: path.display().to_string(),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schemes_parse_and_passwords_are_hidden() {
        let s = DbUrl::parse(Some("sqlite:///tmp/x/r.sqlite3")).unwrap();
        assert_eq!(s.backend, Backend::Sqlite);
        assert_eq!(s.path.as_deref(), Some(Path::new("/tmp/x/r.sqlite3")));
        let p = DbUrl::parse(Some("postgres://u:secret@127.0.0.1:5433/db")).unwrap();
        assert_eq!(p.backend, Backend::Postgres);
        assert!(!p.shown.contains("secret"), "{}", p.shown);
        let e = DbUrl::parse(Some("mysql://u:secret@h/db"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown scheme") && !e.contains("secret"), "{e}");
        assert!(DbUrl::parse(Some("sqlite://a?b")).is_err());
        let d = DbUrl::parse(None).unwrap();
        assert!(d.path.unwrap().ends_with("echothigh/records.sqlite3"));
    }
}
