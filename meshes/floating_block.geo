// floating_block.geo -- a small block resting on a foundation block.
// Foundation: x in [0, 4], y in [0, 2].  Small block: x in [1.5, 2.5], y in [2, 3].
// The foundation top consists of "found_top_left" (x in [0, 1.5]), the
// conforming contact curve "interface" (x in [1.5, 2.5], = bottom of the
// small block, one curve shared by both surfaces) and "found_top_right".
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

hf = 0.15;   // far size (foundation corners)
hb = 0.05;   // size around the small block

Point(1) = {0, 0, 0, hf};
Point(2) = {4, 0, 0, hf};
Point(3) = {4, 2, 0, hf};
Point(4) = {2.5, 2, 0, hb};
Point(5) = {1.5, 2, 0, hb};
Point(6) = {0, 2, 0, hf};
Point(7) = {2.5, 3, 0, hb};
Point(8) = {1.5, 3, 0, hb};

Line(1) = {1, 2};   // found_bottom
Line(2) = {2, 3};   // found_right
Line(3) = {3, 4};   // found_top_right
Line(4) = {4, 5};   // interface
Line(5) = {5, 6};   // found_top_left
Line(6) = {6, 1};   // found_left
Line(7) = {4, 7};   // block_right
Line(8) = {7, 8};   // block_top
Line(9) = {8, 5};   // block_left

Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
Curve Loop(2) = {-4, 7, 8, 9};
Plane Surface(2) = {2};

Physical Surface("foundation") = {1};
Physical Surface("block") = {2};
Physical Curve("found_bottom") = {1};
Physical Curve("found_right") = {2};
Physical Curve("found_top_right") = {3};
Physical Curve("interface") = {4};
Physical Curve("found_top_left") = {5};
Physical Curve("found_left") = {6};
Physical Curve("block_right") = {7};
Physical Curve("block_top") = {8};
Physical Curve("block_left") = {9};
