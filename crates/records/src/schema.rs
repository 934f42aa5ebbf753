//! The versioned schema: migrations under `migrations/sqlite` and
//! `migrations/postgres` (same version numbers, same tables and columns;
//! `tests/suite/schema_parity.rs`), applied on open, and the refusal of a
//! database migrated by a newer echothigh.

use crate::{Backend, RecordsError};
use sqlx::migrate::Migrator;
use sqlx::{AnyPool, Row};

static SQLITE: Migrator = sqlx::migrate!("./migrations/sqlite");
static POSTGRES: Migrator = sqlx::migrate!("./migrations/postgres");

/// The migrations of `backend`.
pub fn migrator(backend: Backend) -> &'static Migrator {
    match backend {
        Backend::Sqlite => &SQLITE,
        Backend::Postgres => &POSTGRES,
    }
}

/// The newest schema version this build knows.
pub fn known_version(backend: Backend) -> i64 {
    migrator(backend)
        .iter()
        .map(|m| m.version)
        .max()
        .unwrap_or(0)
}

/// The newest version applied to the database (0 for a new one).
pub(crate) async fn applied_version(
    pool: &AnyPool,
    backend: Backend,
    db: &str,
) -> Result<i64, RecordsError> {
    // The one dialect-specific query: where each lists its tables.
    let exists = match backend {
        Backend::Sqlite => {
            "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name = '_sqlx_migrations'"
        }
        Backend::Postgres => {
            "SELECT COUNT(*) FROM information_schema.tables \
             WHERE table_schema = current_schema() AND table_name = '_sqlx_migrations'"
        }
    };
    let n: i64 = sqlx::query(exists)
        .fetch_one(pool)
        .await
        .and_then(|r| r.try_get(0))
        .map_err(|e| crate::store::db_error(db, "reading the schema version", e))?;
    if n == 0 {
        return Ok(0);
    }
    let v: Option<i64> = sqlx::query("SELECT MAX(version) FROM _sqlx_migrations")
        .fetch_one(pool)
        .await
        .and_then(|r| r.try_get(0))
        .map_err(|e| crate::store::db_error(db, "reading the schema version", e))?;
    Ok(v.unwrap_or(0))
}

/// Refuses a newer schema, then applies the missing migrations.
pub(crate) async fn migrate(
    pool: &AnyPool,
    backend: Backend,
    db: &str,
) -> Result<(), RecordsError> {
    let found = applied_version(pool, backend, db).await?;
    let known = known_version(backend);
    if found > known {
        return Err(RecordsError::NewerSchema {
            db: db.to_string(),
            found,
            known,
        });
    }
    migrator(backend)
        .run(pool)
        .await
        .map_err(|source| match source {
            sqlx::migrate::MigrateError::Execute(e) => {
                crate::store::db_error(db, "migrating the schema", e)
            }
            source => RecordsError::Migrate {
                db: db.to_string(),
                source,
            },
        })
}
