//! A version-1 database (migration 0001 only, as the first echothigh with
//! records wrote it) holding a trainee's finished case is upgraded on open
//! to the newest schema: its rows are kept and read back as they were, the
//! Doppler tables (0002) and the unique-id columns (0003) are there, empty
//! or NULL for the old rows. On SQLite, and on PostgreSQL when
//! `ECHOTHIGH_TEST_POSTGRES` names a server.

use crate::common;

use echothigh_records::{schema, Backend, BlockingStore};
use sqlx::{Connection, Row};

/// Migrates `url` with the first migration of `backend` only (a copy of
/// this crate's own 0001 file: same checksum as the embedded one).
fn version_1(url: &str, backend: &str) {
    let dir = tempfile::tempdir().unwrap();
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("migrations")
        .join(backend)
        .join("0001_records.sql");
    std::fs::copy(&src, dir.path().join("0001_records.sql")).unwrap();
    common::block_on(async {
        sqlx::any::install_default_drivers();
        let m = sqlx::migrate::Migrator::new(dir.path()).await.unwrap();
        assert_eq!(m.iter().count(), 1);
        let mut c = sqlx::AnyConnection::connect(url).await.unwrap();
        m.run(&mut c).await.unwrap();
        c.close().await.ok();
    });
}

/// One query's single integer.
fn scalar(url: &str, sql: &str) -> Option<i64> {
    common::block_on(async {
        let mut c = sqlx::AnyConnection::connect(url).await.unwrap();
        let v: Option<i64> = sqlx::query(sql)
            .fetch_one(&mut c)
            .await
            .unwrap()
            .try_get(0)
            .unwrap();
        c.close().await.ok();
        v
    })
}

#[test]
fn a_version_1_database_keeps_its_rows_and_gains_the_new_tables() {
    for db in common::all() {
        let backend = db.kind;
        if let Some(dir) = &db.dir {
            // SQLite creates the file on connect with mode=rwc only.
            std::fs::File::create(dir.path().join("records.sqlite3")).unwrap();
        }
        version_1(&db.url, backend);
        assert_eq!(
            scalar(&db.url, "SELECT MAX(version) FROM _sqlx_migrations"),
            Some(1)
        );
        for sql in [
            "INSERT INTO trainees (name, created_ms) VALUES ('Old', 1000)",
            "INSERT INTO sessions (trainee_id, protocol, host, started_ms, ended_ms) VALUES (1, 'two-point', 'h', 2000, 9000)",
            "INSERT INTO case_attempts (session_id, case_name, started_ms, finished_ms, protocol, coverage, calls_correct, \
             calls_total, pressure_adequate, excessive_force_on_tail, duration, peak_force, mean_force, missed) \
             VALUES (1, 'normal-average', 2100, 8000, 'two-point', 0.5, 1, 2, 0.75, 0, 42.5, 18.25, 9.5, '[]')",
            "INSERT INTO events (case_id, seq, t_start, t_end, vein, s, peak_force, min_lumen_ratio, artery_deformed, \
             coapted, slide, force_trace) VALUES (1, 0, 1.0, 2.5, 'cfv', 0.02, 18.25, 0.05, 1, 1, 0.0, '[[1.0,0.0],[2.0,18.25]]')",
            "INSERT INTO calls (case_id, seq, site, vein, s, finding, truth, t) \
             VALUES (1, 0, 'cfv', 'cfv', 0.02, 'normal', 'normal', 3.0)",
        ] {
            common::execute(&db.url, sql);
        }

        let store = BlockingStore::open(Some(&db.url)).unwrap();
        let kind = if backend == "sqlite" {
            Backend::Sqlite
        } else {
            Backend::Postgres
        };
        assert_eq!(
            scalar(&db.url, "SELECT MAX(version) FROM _sqlx_migrations"),
            Some(schema::known_version(kind)),
            "{backend}: migrated to the newest version"
        );
        assert_eq!(schema::known_version(kind), 3);
        // The old rows, read back through the store.
        let h = store.history("Old").unwrap();
        assert_eq!(h.sessions.len(), 1, "{backend}");
        let s = &h.sessions[0];
        assert_eq!(
            (s.protocol.as_str(), s.started_ms, s.ended_ms),
            ("two-point", 2000, Some(9000))
        );
        let d = store.case_detail(s.cases[0].id).unwrap();
        assert_eq!(d.case, "normal-average");
        assert_eq!(d.events.len(), 1);
        assert_eq!(d.events[0].peak_force, 18.25);
        assert_eq!(d.events[0].force_trace, vec![[1.0, 0.0], [2.0, 18.25]]);
        assert_eq!(d.calls.len(), 1);
        let score = d.score.expect("the finished case's score");
        assert_eq!((score.calls_correct, score.calls_total), (1, 2));
        assert_eq!((score.coverage, score.duration), (0.5, 42.5));
        assert!(d.doppler_calls.is_empty());
        // The new tables exist (empty) and the new columns are NULL.
        for t in ["doppler_calls", "doppler_site_scores"] {
            assert_eq!(
                scalar(&db.url, &format!("SELECT COUNT(*) FROM {t}")),
                Some(0),
                "{backend}: {t}"
            );
        }
        assert_eq!(
            scalar(
                &db.url,
                "SELECT doppler_total FROM case_attempts WHERE id = 1"
            ),
            None
        );
        assert_eq!(
            scalar(&db.url, "SELECT COUNT(*) FROM sessions WHERE uid IS NULL"),
            Some(1)
        );
        assert_eq!(
            scalar(
                &db.url,
                "SELECT COUNT(*) FROM case_attempts WHERE uid IS NULL"
            ),
            Some(1)
        );
    }
}
