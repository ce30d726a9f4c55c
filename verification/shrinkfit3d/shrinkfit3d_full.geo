// shrinkfit3d_full.geo -- the whole ring of shrinkfit3d.geo (see there),
// with the physical points "in_0", ..., "out_270" where
// shrinkfit3d_torque.toml turns the inner tube and holds the outer one.
// n, N: set by scripts/verify.
full = 1;
Include "shrinkfit3d.geo.inc";
Physical Volume("inner") = {vi[]};
Physical Volume("outer") = {vo[]};
