-- echothigh records, schema version 2 (SQLite dialect): Doppler calls
-- (issue 14, echothigh_exam::doppler). The PostgreSQL file of the same
-- version has the same tables and columns (tests/schema_parity.rs).
-- `flow` is phasic | continuous | absent; flags are 0/1 integers.

CREATE TABLE doppler_calls (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    case_id INTEGER NOT NULL REFERENCES case_attempts(id),
    seq INTEGER NOT NULL,
    site TEXT NOT NULL,
    vein TEXT NOT NULL,
    s REAL NOT NULL,
    flow TEXT NOT NULL,
    augments INTEGER NOT NULL CHECK (augments IN (0, 1)),
    truth_flow TEXT NOT NULL,
    truth_augments INTEGER NOT NULL CHECK (truth_augments IN (0, 1)),
    t REAL NOT NULL
);

-- The Doppler score per site (a missing call: flow and augments NULL).
CREATE TABLE doppler_site_scores (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    case_id INTEGER NOT NULL REFERENCES case_attempts(id),
    seq INTEGER NOT NULL,
    site TEXT NOT NULL,
    flow TEXT,
    augments INTEGER CHECK (augments IN (0, 1)),
    truth_flow TEXT NOT NULL,
    truth_augments INTEGER NOT NULL CHECK (truth_augments IN (0, 1))
);

-- CaseScore::doppler's counts (NULL for cases finished before version 2).
ALTER TABLE case_attempts ADD COLUMN doppler_correct INTEGER;
ALTER TABLE case_attempts ADD COLUMN doppler_total INTEGER;

CREATE INDEX doppler_calls_case ON doppler_calls(case_id);
CREATE INDEX doppler_site_scores_case ON doppler_site_scores(case_id);
