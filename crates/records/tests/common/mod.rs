//! The databases every records test runs on: a SQLite file in a temp
//! directory and, when `ECHOTHIGH_TEST_POSTGRES` names a server, a fresh
//! PostgreSQL database on it (one per call, so tests do not share rows or
//! schema versions). `ECHOTHIGH_REQUIRE_POSTGRES=1` without a server fails.
#![allow(dead_code)]

use sqlx::Connection;
use std::sync::atomic::{AtomicU32, Ordering};

/// A database to test on; keeps its temp directory alive.
pub struct TestDb {
    /// `sqlite` or `postgres`.
    pub kind: &'static str,
    /// Its URL.
    pub url: String,
    /// The SQLite file's directory.
    pub dir: Option<tempfile::TempDir>,
}

/// A fresh SQLite file.
pub fn sqlite() -> TestDb {
    let dir = tempfile::tempdir().expect("temp dir");
    let url = format!("sqlite://{}", dir.path().join("records.sqlite3").display());
    TestDb {
        kind: "sqlite",
        url,
        dir: Some(dir),
    }
}

/// The PostgreSQL server's base URL, or `None` (skipped, said on stderr).
pub fn postgres_base() -> Option<String> {
    match std::env::var("ECHOTHIGH_TEST_POSTGRES") {
        Ok(u) if !u.is_empty() => Some(u),
        _ => {
            assert!(
                std::env::var("ECHOTHIGH_REQUIRE_POSTGRES").as_deref() != Ok("1"),
                "ECHOTHIGH_REQUIRE_POSTGRES=1 but ECHOTHIGH_TEST_POSTGRES is unset (run .ci/postgres.sh)"
            );
            eprintln!("ECHOTHIGH_TEST_POSTGRES unset: skipped the PostgreSQL half");
            None
        }
    }
}

/// A fresh database on the PostgreSQL server, or `None` (skipped).
pub fn postgres() -> Option<TestDb> {
    static N: AtomicU32 = AtomicU32::new(0);
    let base = postgres_base()?;
    let name = format!(
        "echothigh_t_{}_{}_{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .subsec_nanos()
    );
    block_on(async {
        sqlx::any::install_default_drivers();
        let mut c = sqlx::AnyConnection::connect(&base)
            .await
            .expect("connect to the test server");
        sqlx::query(&format!("CREATE DATABASE {name}"))
            .execute(&mut c)
            .await
            .expect("create a test database");
        c.close().await.ok();
    });
    let cut = base.rfind('/').expect("a database in the URL");
    Some(TestDb {
        kind: "postgres",
        url: format!("{}/{name}", &base[..cut]),
        dir: None,
    })
}

/// SQLite, then PostgreSQL when there is a server.
pub fn all() -> Vec<TestDb> {
    let mut v = vec![sqlite()];
    v.extend(postgres());
    v
}

/// Runs `f` on a private current-thread runtime.
pub fn block_on<F: std::future::Future>(f: F) -> F::Output {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime")
        .block_on(f)
}

/// Executes raw SQL on `url` (test set-up only).
pub fn execute(url: &str, sql: &str) {
    block_on(async {
        sqlx::any::install_default_drivers();
        let mut c = sqlx::AnyConnection::connect(url).await.expect("connect");
        sqlx::query(sql).execute(&mut c).await.expect(sql);
        c.close().await.ok();
    })
}
