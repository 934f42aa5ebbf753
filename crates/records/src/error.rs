//! What can go wrong with the records, each error naming the file or URL.

/// An error of the records store. Every variant names the database (a file
/// path or a URL with its password hidden) so the message alone says where.
#[derive(Debug, thiserror::Error)]
pub enum RecordsError {
    /// The URL is neither `sqlite://PATH` nor `postgres://…`.
    #[error("database URL `{url}`: unknown scheme (use sqlite://PATH or postgres://USER@HOST/DB)")]
    BadScheme {
        /// The URL as given (password hidden).
        url: String,
    },
    /// No default location: the user's data directory is unknown.
    #[error("no data directory for the default records file (set $HOME or pass --db URL)")]
    NoDataDir,
    /// The SQLite file exists but is not a SQLite database.
    #[error("{path}: not a database (corrupt or another kind of file); move it aside or pass another --db")]
    NotADatabase {
        /// The file.
        path: String,
    },
    /// The SQLite file or its directory cannot be written.
    #[error("{path}: read-only ({why}); the records need a writable file and directory")]
    ReadOnly {
        /// The file or directory.
        path: String,
        /// What is read-only.
        why: String,
    },
    /// The database was migrated by a newer echothigh.
    #[error("{db}: schema version {found} is newer than this echothigh (knows {known}); update echothigh")]
    NewerSchema {
        /// The database.
        db: String,
        /// The newest version applied to it.
        found: i64,
        /// The newest version this binary knows.
        known: i64,
    },
    /// The database server could not be reached.
    #[error("{db}: cannot reach the database server: {source}")]
    Unreachable {
        /// The database URL (password hidden).
        db: String,
        /// The connection error.
        source: sqlx::Error,
    },
    /// A trainee's name is not acceptable.
    #[error("trainee name `{name}`: {why}")]
    BadName {
        /// The name as given.
        name: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// No trainee of that name in the records.
    #[error("{db}: no trainee named `{name}`")]
    UnknownTrainee {
        /// The database.
        db: String,
        /// The name asked for.
        name: String,
    },
    /// A stored value could not be read back (a foreign or damaged row).
    #[error("{db}: {table} row {id}: {why}")]
    BadRow {
        /// The database.
        db: String,
        /// The table.
        table: &'static str,
        /// The row's id.
        id: i64,
        /// What is wrong.
        why: String,
    },
    /// Applying the migrations failed.
    #[error("{db}: migrating the schema: {source}")]
    Migrate {
        /// The database.
        db: String,
        /// The migration error.
        source: sqlx::migrate::MigrateError,
    },
    /// Any other database error, with what was being done.
    #[error("{db}: {doing}: {source}")]
    Db {
        /// The database.
        db: String,
        /// What was being done (`inserting an event`, …).
        doing: &'static str,
        /// The database's error.
        source: sqlx::Error,
    },
    /// A fallback journal line could not be read or written.
    #[error("fallback journal {path}, line {line}: {why}")]
    Journal {
        /// The journal file.
        path: String,
        /// The line (from 1; 0: the file as a whole).
        line: usize,
        /// What is wrong.
        why: String,
    },
    /// A journal's record names a case whose `case` line is not in it.
    #[error("fallback journal {path}, line {line}: a {kind} record of case `{case}` ({uid}) comes before the case's own line")]
    Orphan {
        /// The journal file.
        path: String,
        /// The line (from 1).
        line: usize,
        /// The record's kind.
        kind: &'static str,
        /// The case's name.
        case: String,
        /// The case's unique id.
        uid: String,
    },
    /// The store's worker thread is gone (it panicked or was shut down).
    #[error("{db}: the records thread has stopped")]
    WorkerGone {
        /// The database.
        db: String,
    },
    /// Creating the records' directory or runtime failed.
    #[error("{path}: {source}")]
    Io {
        /// The path or the thing being created.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
}
