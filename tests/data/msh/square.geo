// Fixture for tests/mesh_reader.rs (gmsh 4.8.4):
//   gmsh -2 -format msh41 square.geo -o square_ascii41.msh
//   gmsh -2 -format msh22 square.geo -o square_ascii22.msh
//   gmsh -2 -format msh41 -save_parametric square.geo -o square_param_ascii41.msh
// The binary files are re-saved from the ASCII ones, so that their doubles are
// exactly those of the ASCII text (gmsh writes ASCII with %.16g, which does
// not always round-trip; binary straight from the .geo can differ in the last bit):
//   gmsh square_ascii41.msh -format msh41 -bin -save -o square_bin41.msh
//   gmsh square_param_ascii41.msh -format msh41 -bin -save_parametric -save -o square_param_bin41.msh
// Unit square split by a vertical interface at x = 0.5 into two surfaces.
lc = 0.25;
Point(1) = {0, 0, 0, lc};
Point(2) = {0.5, 0, 0, lc};
Point(3) = {1, 0, 0, lc};
Point(4) = {1, 1, 0, lc};
Point(5) = {0.5, 1, 0, lc};
Point(6) = {0, 1, 0, lc};
Line(1) = {1, 2};   // bottom, left half
Line(2) = {2, 3};   // bottom, right half
Line(3) = {3, 4};   // right
Line(4) = {4, 5};   // top, right half
Line(5) = {5, 6};   // top, left half
Line(6) = {6, 1};   // left
Line(7) = {2, 5};   // interface
Curve Loop(1) = {1, 7, 5, 6};
Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, 4, -7};
Plane Surface(2) = {2};
Physical Curve("left") = {6};
Physical Curve("right") = {3};
Physical Curve("top") = {4, 5};
Physical Curve("bottom") = {1, 2};
Physical Curve("interface") = {7};
Physical Point("corner") = {1};
Physical Surface("body_left") = {1};
Physical Surface("body_right") = {2};
// Both surfaces also belong to a second physical group, so each triangle
// belongs to two groups (tests entities with several physical tags).
Physical Surface("all") = {1, 2};
