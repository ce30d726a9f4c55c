// disc_gap.geo -- a stiff half-disc (radius 1) above a soft block 6 x 3,
// 5e-4 apart: held only by contact once the load closes the gap (issue 36).
// About 5 k nodes.
lc = 0.08; lcf = 0.01;
Point(1) = {-3, -3, 0, lc*4}; Point(2) = {3, -3, 0, lc*4}; Point(3) = {3, 0, 0, lc};
Point(4) = {0.6, 0, 0, lcf}; Point(5) = {-0.6, 0, 0, lcf}; Point(6) = {-3, 0, 0, lc};
Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,5}; Line(5) = {5,6}; Line(6) = {6,1};
Curve Loop(1) = {1,2,3,4,5,6}; Plane Surface(1) = {1};
// disc: centre (0, 1.0005), radius 1 -> bottom at y = 0.0005 (a small initial gap)
Point(10) = {0, 1.0005, 0, lc}; Point(11) = {1, 1.0005, 0, lc}; Point(12) = {-1, 1.0005, 0, lc};
Point(13) = {0, 0.0005, 0, lcf}; Point(14) = {0.5, 1.0005-Sqrt(0.75), 0, lcf}; Point(15) = {-0.5, 1.0005-Sqrt(0.75), 0, lcf};
Circle(11) = {12, 10, 15}; Circle(12) = {15, 10, 13}; Circle(13) = {13, 10, 14}; Circle(14) = {14, 10, 11};
Line(15) = {11, 12};
Curve Loop(2) = {11,12,13,14,15}; Plane Surface(2) = {2};
Physical Surface("block") = {1}; Physical Surface("disc") = {2};
Physical Curve("bottom") = {1}; Physical Curve("sides") = {2, 6};
Physical Curve("block_top") = {3,4,5}; Physical Curve("disc_arc") = {11,12,13,14};
Physical Curve("disc_top") = {15};
