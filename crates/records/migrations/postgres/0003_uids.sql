-- echothigh records, schema version 3 (PostgreSQL dialect): a unique id per
-- session and per case attempt, written by the live exam and carried by the
-- fallback journal (crates/records/src/journal.rs), so that replaying a
-- journal (echothigh records import) finds the rows already there and adds
-- only the missing ones. NULL for rows written before version 3 (a UNIQUE
-- index admits many NULLs on both backends). Same columns as the
-- SQLite file of this version (tests/schema_parity.rs).

ALTER TABLE sessions ADD COLUMN uid TEXT;
ALTER TABLE case_attempts ADD COLUMN uid TEXT;

CREATE UNIQUE INDEX sessions_uid ON sessions(uid);
CREATE UNIQUE INDEX case_attempts_uid ON case_attempts(uid);
