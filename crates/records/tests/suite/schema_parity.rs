//! The SQLite and PostgreSQL migrations of each version give the same
//! tables with the same columns (names, order, and nullability), read from
//! live databases migrated by the store itself.

use crate::common;

use echothigh_records::BlockingStore;
use sqlx::{Connection, Row};

type Columns = Vec<(String, String, bool)>; // (table, column, nullable)

fn columns(url: &str, sqlite: bool) -> Columns {
    let sql = if sqlite {
        "SELECT m.name, p.name, p.\"notnull\", p.pk FROM sqlite_master m, pragma_table_info(m.name) p \
         WHERE m.type = 'table' AND m.name NOT LIKE 'sqlite_%' AND m.name <> '_sqlx_migrations' \
         ORDER BY m.name, p.cid"
    } else {
        "SELECT table_name::text, column_name::text, CASE WHEN is_nullable = 'NO' THEN 1 ELSE 0 END::bigint, \
         0::bigint FROM information_schema.columns WHERE table_schema = current_schema() \
         AND table_name <> '_sqlx_migrations' ORDER BY table_name, ordinal_position"
    };
    common::block_on(async {
        sqlx::any::install_default_drivers();
        let mut c = sqlx::AnyConnection::connect(url).await.unwrap();
        let rows = sqlx::query(sql).fetch_all(&mut c).await.unwrap();
        rows.iter()
            .map(|r| {
                // SQLite reports an INTEGER PRIMARY KEY as nullable in
                // `notnull`; it is not (it is the rowid).
                let not_null = r.get::<i64, _>(2) != 0 || r.get::<i64, _>(3) != 0;
                (r.get::<String, _>(0), r.get::<String, _>(1), !not_null)
            })
            .collect()
    })
}

#[test]
fn sqlite_and_postgres_schemas_have_the_same_tables_and_columns() {
    let lite = common::sqlite();
    BlockingStore::open(Some(&lite.url)).unwrap();
    let l = columns(&lite.url, true);
    assert!(
        l.iter()
            .any(|(t, c, n)| t == "events" && c == "force_trace" && !n),
        "{l:?}"
    );
    assert_eq!(l.iter().filter(|(t, ..)| t == "trainees").count(), 3);
    let Some(pg) = common::postgres() else { return };
    BlockingStore::open(Some(&pg.url)).unwrap();
    let p = columns(&pg.url, false);
    assert_eq!(l, p);
}
