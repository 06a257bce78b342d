-- As migrations/sqlite/0006: the row /health rewrites to learn whether
-- writes succeed again.
CREATE TABLE write_probe (
    id BIGINT PRIMARY KEY CHECK (id = 1),
    at DOUBLE PRECISION NOT NULL
);
