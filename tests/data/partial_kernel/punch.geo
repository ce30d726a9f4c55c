hf = 0.3; hp = 0.1;
Point(1) = {-3, 0, 0, hf}; Point(2) = {3, 0, 0, hf}; Point(3) = {3, 2, 0, hp*2}; Point(4) = {-3, 2, 0, hp*2};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
// punch: bottom y = 2, rounded corners r = 0.2
Point(10) = {-0.8, 2, 0, hp}; Point(11) = {0.8, 2, 0, hp};
Point(12) = {1, 2.2, 0, hp}; Point(13) = {1, 3, 0, hp}; Point(14) = {0, 3, 0, hp}; Point(15) = {-1, 3, 0, hp}; Point(16) = {-1, 2.2, 0, hp};
Point(17) = {0.8, 2.2, 0, hp}; Point(18) = {-0.8, 2.2, 0, hp};
Line(10) = {10, 11}; Circle(11) = {11, 17, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 15}; Line(15) = {15, 16}; Circle(16) = {16, 18, 10};
Curve Loop(2) = {10, 11, 12, 13, 14, 15, 16}; Plane Surface(2) = {2};
Physical Surface("foundation") = {1};
Physical Surface("punch") = {2};
Physical Curve("found_bottom") = {1};
Physical Curve("found_top") = {3};
Physical Curve("punch_bottom") = {16, 10, 11};
Physical Curve("punch_top") = {13, 14};
Physical Point("punch_top_mid") = {14};
