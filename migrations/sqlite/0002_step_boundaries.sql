-- Boundary curves of each stored step: a JSON array of
-- mpm::boundary::BoundaryOutput (body, hole, points, bspline, polyline).
ALTER TABLE steps ADD COLUMN boundaries TEXT NOT NULL DEFAULT '[]';
