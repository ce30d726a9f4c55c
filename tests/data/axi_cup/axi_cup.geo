// Meridian section (x = r, y = z) of a closed-end thick cylinder, a cup:
// outer radius 2, bore radius 1, bottom 1 thick, height 3, with a plug
// (radius 0.9, 0.4 thick) seated on the bore bottom: the seat r <= 0.9 is a
// conforming contact curve (shared nodes, one copy per body). Both bodies
// reach the axis r = 0 (triangles with one or two vertices on it).
h = 0.15;
Point(1) = {0, 0, 0, h}; Point(2) = {2, 0, 0, h}; Point(3) = {2, 3, 0, h};
Point(4) = {1, 3, 0, h}; Point(5) = {1, 1, 0, h}; Point(7) = {0.9, 1, 0, h}; Point(6) = {0, 1, 0, h};
Point(8) = {0.9, 1.4, 0, h}; Point(9) = {0, 1.4, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4};
Line(4) = {4, 5}; Line(5) = {5, 7}; Line(7) = {7, 6}; Line(6) = {6, 1};
Line(8) = {7, 8}; Line(9) = {8, 9}; Line(10) = {9, 6};
Curve Loop(1) = {1, 2, 3, 4, 5, 7, 6}; Plane Surface(1) = {1};
Curve Loop(2) = {-7, 8, 9, 10}; Plane Surface(2) = {2};
Physical Surface("cup") = {1};
Physical Surface("plug") = {2};
Physical Curve("bottom") = {1};
Physical Curve("outer") = {2};
Physical Curve("rim") = {3};
Physical Curve("bore") = {4, 5};
Physical Curve("seat") = {7};
Physical Curve("plug_top") = {9};
Physical Curve("axis") = {6, 10};
Physical Point("rim_out") = {3};
