// sliding_block3d.geo -- a block sliding on a plane, 3D (issue 46,
// docs/verification_3d.md §7h). Units m.
// Block: [-0.5, 0.5]^2 x [0, 0.25]; foundation: [-0.75, 0.75]^2 x [-0.5, 0],
// meshed apart (non-matching faces at z = 0: the block's bottom, the slave,
// lies inside the foundation's top, the master). Unstructured tetrahedra of
// size h in the block and 1.3 h in the foundation (set by scripts/verify:
// coarse 0.1, fine 0.05), so the mesh has no preferred direction in the
// plane; the rows' tangent frames are (x, y) up to sign (n = z).
SetFactory("OpenCASCADE");
DefineConstant[ h = {0.1, Name "h"} ];
Box(1) = {-0.5, -0.5, 0, 1, 1, 0.25};
Box(2) = {-0.75, -0.75, -0.5, 1.5, 1.5, 0.5};
MeshSize{ PointsOf{ Volume{1}; } } = h;
MeshSize{ PointsOf{ Volume{2}; } } = 1.3 * h;
Physical Volume("block") = {1};
Physical Volume("foundation") = {2};
// OpenCASCADE numbers a box's faces x-, x+, y-, y+, z-, z+.
Physical Surface("block_bottom") = {5};
Physical Surface("block_top") = {6};
Physical Surface("foundation_top") = {12};
Physical Surface("foundation_bottom") = {11};
