// shrinkfit3d.geo -- the shrink fit of verification/shrinkfit (two thick
// steel tubes, radial interference delta) in 3D (issue 46,
// docs/verification_3d.md §7i). Units m; z is the axis.
// Inner tube a <= r <= c + delta, outer tube c <= r <= b, both 0 <= z <= L:
// the inner tube's outer radius exceeds the outer tube's bore by delta, an
// intended overlap (`interference = true`). Each tube is its r-z section
// (shrinkfit.geo's structured triangles: n through each wall, n along the
// inner tube and n + 1 along the outer one, so the interface is
// non-matching along z) revolved about z with N layers per quarter turn:
// the two tubes have nodes at the same angles, so their faceted surfaces
// are parallel and the interference is the same all round (facets of
// different angles would differ by the sagitta c (1 - cos(pi/4N)), more
// than delta). full = 0: a quarter (0 <= phi <= 90 deg; symmetry planes
// "sym_y0" (y = 0) and "sym_x0" (x = 0)); full = 1: the whole ring, and
// physical points at the angles 0, 90, 180, 270 deg on the inner tube's
// bore ("in_0", "in_90", "in_180", "in_270": the nodes (a, phi, 0) and
// (a, phi, L)) and on the outer tube's outer surface ("out_0", ...), where
// the torque model holds and turns the tubes.
// n, N: set by scripts/verify. The mesh: shrinkfit3d.geo.inc.
full = 0;
Include "shrinkfit3d.geo.inc";
Physical Volume("inner") = {vi[]};
Physical Volume("outer") = {vo[]};
