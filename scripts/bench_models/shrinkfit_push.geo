// shrinkfit_push.geo -- the benchmark family of frictional ssn at scale
// (issue 42 §2, BENCHMARKS.md): two steel tubes shrink-fitted, AXISYMMETRIC
// (x = r, y = z), then the inner one pushed out axially against Coulomb
// friction (shrinkfit_push.toml). As verification/shrinkfit.geo, but the
// interface is refined on its own: nz segments on the inner tube's side and
// 4 nz / 5 on the outer tube's (a 5:4 non-matching pair), nr elements
// through each wall graded towards the interface, and a smaller
// interference delta so that it stays below half a segment.
// Nodes about 2 (nr + 1)(nz + 1): nz = 400, nr = 12 -> 10 k; nz = 800,
// nr = 31 -> 50 k; nz = 1600, nr = 62 -> 200 k.
DefineConstant[ nz = {400, Name "nz"}, nr = {12, Name "nr"},
                delta = {1.0e-4, Name "delta"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
a = 0.5; c = 1.0; b = 1.5; L = 0.5;
no = Round(4 * nz / 5);

Point(1) = {a, 0, 0};
Point(2) = {c + delta, 0, 0};
Point(3) = {c + delta, L, 0};
Point(4) = {a, L, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve {1} = nr + 1 Using Progression 0.93;
Transfinite Curve {3} = nr + 1 Using Progression 1 / 0.93;
Transfinite Curve {2, 4} = nz + 1;
Transfinite Surface {1} Alternate;

Point(11) = {c, 0, 0};
Point(12) = {b, 0, 0};
Point(13) = {b, L, 0};
Point(14) = {c, L, 0};
Line(11) = {11, 12};
Line(12) = {12, 13};
Line(13) = {13, 14};
Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(2) = {2};
Transfinite Curve {11} = nr + 1 Using Progression 1 / 0.93;
Transfinite Curve {13} = nr + 1 Using Progression 0.93;
Transfinite Curve {12, 14} = no + 1;
Transfinite Surface {2} Alternate;

Physical Surface("inner") = {1};
Physical Surface("outer") = {2};
Physical Curve("inner_bottom") = {1};
Physical Curve("inner_contact") = {2};
Physical Curve("inner_top") = {3};
Physical Curve("inner_bore") = {4};
Physical Curve("outer_bottom") = {11};
Physical Curve("outer_surface") = {12};
Physical Curve("outer_top") = {13};
Physical Curve("outer_contact") = {14};
