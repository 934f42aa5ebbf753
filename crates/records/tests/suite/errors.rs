//! A records file that is corrupt, read-only, or from a newer schema, a
//! server that is not there, and a bad URL each give a clear error naming
//! the file or URL, and the file is left exactly as it was.

use crate::common;

use echothigh_records::{BlockingStore, RecordsError};
use std::os::unix::fs::PermissionsExt;

fn open_err(url: &str) -> RecordsError {
    BlockingStore::open(Some(url)).expect_err(url)
}

#[test]
fn a_file_that_is_not_sqlite_is_refused_and_left_alone() {
    let db = common::sqlite();
    let path = db.dir.as_ref().unwrap().path().join("records.sqlite3");
    let junk: Vec<u8> = (0..4096u32).map(|i| (i * 31 % 251) as u8).collect();
    std::fs::write(&path, &junk).unwrap();
    let e = open_err(&db.url);
    assert!(matches!(e, RecordsError::NotADatabase { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains(&path.display().to_string()) && msg.contains("not a database"),
        "{msg}"
    );
    assert_eq!(std::fs::read(&path).unwrap(), junk, "the file was changed");
}

#[test]
fn a_sqlite_file_with_a_damaged_header_is_refused_by_sqlite_itself() {
    // The 16-byte magic is right, so only SQLite's own check (the page
    // size at offset 16 must be a power of two in 512..=65536) can catch
    // it: its "not a database" / "corrupt" codes map to the same error.
    let db = common::sqlite();
    BlockingStore::open(Some(&db.url))
        .unwrap()
        .trainee("Cy")
        .unwrap();
    let path = db.dir.as_ref().unwrap().path().join("records.sqlite3");
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[16] = 0x01;
    bytes[17] = 0x23; // page size 291: not a power of two
    std::fs::write(&path, &bytes).unwrap();
    let e = open_err(&db.url);
    assert!(matches!(e, RecordsError::NotADatabase { .. }), "{e}");
    assert!(e.to_string().contains("records.sqlite3"), "{e}");
    assert_eq!(std::fs::read(&path).unwrap(), bytes, "the file was changed");
}

#[test]
fn read_only_file_and_directory_are_named() {
    let db = common::sqlite();
    BlockingStore::open(Some(&db.url))
        .unwrap()
        .trainee("Di")
        .unwrap();
    let dir = db.dir.as_ref().unwrap().path();
    let path = dir.join("records.sqlite3");
    let before = std::fs::read(&path).unwrap();

    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o444)).unwrap();
    let e = open_err(&db.url);
    assert!(matches!(e, RecordsError::ReadOnly { .. }), "{e}");
    assert!(e.to_string().contains(&path.display().to_string()), "{e}");
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).unwrap();

    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o555)).unwrap();
    let e = open_err(&db.url);
    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    assert!(matches!(e, RecordsError::ReadOnly { .. }), "{e}");
    assert!(e.to_string().contains("directory"), "{e}");
    assert_eq!(
        std::fs::read(&path).unwrap(),
        before,
        "the file was changed"
    );
}

#[test]
fn a_newer_schema_is_refused_on_every_backend() {
    for db in common::all() {
        BlockingStore::open(Some(&db.url))
            .unwrap()
            .trainee("Ed")
            .unwrap();
        // What a future echothigh would leave: a migration this build has
        // never heard of.
        let checksum = if db.kind == "sqlite" {
            "X'00'"
        } else {
            "'\\x00'::bytea"
        };
        common::execute(
            &db.url,
            &format!(
                "INSERT INTO _sqlx_migrations (version, description, success, checksum, execution_time) \
                 VALUES (999, 'from the future', TRUE, {checksum}, 0)"
            ),
        );
        let e = open_err(&db.url);
        let known = echothigh_records::schema::known_version(if db.kind == "sqlite" {
            echothigh_records::Backend::Sqlite
        } else {
            echothigh_records::Backend::Postgres
        });
        // 0001 records, 0002 Doppler, 0003 unique ids (the fallback journal's replay).
        assert_eq!(known, 3);
        assert!(
            matches!(
                e,
                RecordsError::NewerSchema {
                    found: 999,
                    known: 3,
                    ..
                }
            ),
            "{e}"
        );
        assert!(
            e.to_string()
                .contains("schema version 999 is newer than this echothigh (knows 3)"),
            "{e}"
        );
    }
}

#[test]
fn an_unreachable_server_and_a_bad_scheme_are_named_without_the_password() {
    // Port 1 on loopback: nothing listens there (tcpmux is never run).
    let e = open_err("postgres://trainer:hunter2@127.0.0.1:1/records");
    assert!(matches!(e, RecordsError::Unreachable { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("127.0.0.1:1") && !msg.contains("hunter2"),
        "{msg}"
    );
    let e = open_err("mysql://trainer:hunter2@127.0.0.1/records");
    assert!(matches!(e, RecordsError::BadScheme { .. }), "{e}");
    assert!(!e.to_string().contains("hunter2"), "{e}");
}

#[test]
fn a_missing_file_and_its_directories_are_created() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a/b/records.sqlite3");
    let url = format!("sqlite://{}", path.display());
    BlockingStore::open(Some(&url))
        .unwrap()
        .trainee("Flo")
        .unwrap();
    let head = std::fs::read(&path).unwrap();
    assert_eq!(&head[..16], b"SQLite format 3\0");
}
