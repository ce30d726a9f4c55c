// tests/data/two_on_one (tests/forces.rs); meshed by gmsh -2 -format msh41.
// Two blocks side by side on a foundation; one slave group over both bottoms.
h = 0.1;
Point(1) = {0, 0, 0, h}; Point(2) = {4, 0, 0, h}; Point(3) = {4, 1, 0, h}; Point(4) = {0, 1, 0, h};
Point(5) = {0.5, 1, 0, h*0.7}; Point(6) = {1.5, 1, 0, h*0.7}; Point(7) = {1.5, 2, 0, h*0.7}; Point(8) = {0.5, 2, 0, h*0.7};
Point(9) = {2.5, 1, 0, h*0.7}; Point(10) = {3.5, 1, 0, h*0.7}; Point(11) = {3.5, 1.6, 0, h*0.7}; Point(12) = {2.5, 1.6, 0, h*0.7};
Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,1};
Line(5) = {5,6}; Line(6) = {6,7}; Line(7) = {7,8}; Line(8) = {8,5};
Line(9) = {9,10}; Line(10) = {10,11}; Line(11) = {11,12}; Line(12) = {12,9};
Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1};
Curve Loop(2) = {5,6,7,8}; Plane Surface(2) = {2};
Curve Loop(3) = {9,10,11,12}; Plane Surface(3) = {3};
Physical Surface("foundation") = {1};
Physical Surface("a") = {2};
Physical Surface("b") = {3};
Physical Curve("base") = {1};
Physical Curve("ftop") = {3};
Physical Curve("bottoms") = {5, 9};
Physical Curve("tops") = {7, 11};
Physical Curve("sides") = {6, 8, 10, 12};
