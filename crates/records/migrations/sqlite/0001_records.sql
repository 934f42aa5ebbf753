-- echothigh records, schema version 1 (SQLite dialect).
-- The PostgreSQL file of the same version has the same tables and columns
-- (tests/schema_parity.rs checks it). Times are Unix milliseconds (UTC);
-- lengths m, forces N, durations s; flags are 0/1 integers (the Any driver
-- has no SQLite boolean, so both use integers).

CREATE TABLE trainees (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL UNIQUE,
    created_ms INTEGER NOT NULL
);

CREATE TABLE sessions (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    trainee_id INTEGER NOT NULL REFERENCES trainees(id),
    protocol TEXT NOT NULL,
    host TEXT NOT NULL,
    started_ms INTEGER NOT NULL,
    ended_ms INTEGER
);

CREATE TABLE case_attempts (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    session_id INTEGER NOT NULL REFERENCES sessions(id),
    case_name TEXT NOT NULL,
    started_ms INTEGER NOT NULL,
    finished_ms INTEGER,
    protocol TEXT,
    coverage REAL,
    calls_correct INTEGER,
    calls_total INTEGER,
    pressure_adequate REAL,
    excessive_force_on_tail INTEGER,
    duration REAL,
    peak_force REAL,
    mean_force REAL,
    -- CaseScore::missed as JSON: the diseased stretches never examined.
    missed TEXT
);

CREATE TABLE truth_pieces (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    case_id INTEGER NOT NULL REFERENCES case_attempts(id),
    seq INTEGER NOT NULL,
    vein TEXT NOT NULL,
    s_start REAL NOT NULL,
    s_end REAL NOT NULL,
    kind TEXT NOT NULL
);

CREATE TABLE events (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    case_id INTEGER NOT NULL REFERENCES case_attempts(id),
    seq INTEGER NOT NULL,
    t_start REAL NOT NULL,
    t_end REAL NOT NULL,
    vein TEXT,
    s REAL NOT NULL,
    peak_force REAL NOT NULL,
    min_lumen_ratio REAL NOT NULL,
    artery_deformed INTEGER NOT NULL CHECK (artery_deformed IN (0, 1)),
    coapted INTEGER NOT NULL CHECK (coapted IN (0, 1)),
    slide REAL NOT NULL,
    force_trace TEXT NOT NULL
);

CREATE TABLE calls (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    case_id INTEGER NOT NULL REFERENCES case_attempts(id),
    seq INTEGER NOT NULL,
    site TEXT NOT NULL,
    vein TEXT NOT NULL,
    s REAL NOT NULL,
    finding TEXT NOT NULL,
    truth TEXT NOT NULL,
    t REAL NOT NULL
);

CREATE TABLE coverage_bins (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    case_id INTEGER NOT NULL REFERENCES case_attempts(id),
    seq INTEGER NOT NULL,
    vein TEXT NOT NULL,
    s_start REAL NOT NULL,
    s_end REAL NOT NULL,
    state TEXT NOT NULL
);

CREATE TABLE site_scores (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    case_id INTEGER NOT NULL REFERENCES case_attempts(id),
    seq INTEGER NOT NULL,
    site TEXT NOT NULL,
    finding TEXT,
    truth TEXT NOT NULL,
    pressure_adequate INTEGER NOT NULL CHECK (pressure_adequate IN (0, 1)),
    called_without_adequate_pressure INTEGER NOT NULL CHECK (called_without_adequate_pressure IN (0, 1))
);

CREATE INDEX sessions_trainee ON sessions(trainee_id);
CREATE INDEX case_attempts_session ON case_attempts(session_id);
CREATE INDEX truth_pieces_case ON truth_pieces(case_id);
CREATE INDEX events_case ON events(case_id);
CREATE INDEX calls_case ON calls(case_id);
CREATE INDEX coverage_bins_case ON coverage_bins(case_id);
CREATE INDEX site_scores_case ON site_scores(case_id);
