-- One row that /health rewrites while the database's last write failed for
-- want of space: a write that succeeds says the space is back.
CREATE TABLE write_probe (
    id INTEGER PRIMARY KEY CHECK (id = 1),
    at REAL NOT NULL
);
