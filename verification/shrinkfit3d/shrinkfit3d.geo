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
// n, N, full: set by scripts/verify.
DefineConstant[ n = {6, Name "n"}, N = {16, Name "N"}, full = {0, Name "full"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
a = 0.5; c = 1.0; b = 1.5; L = 0.5; delta = 1.0e-3;

// inner tube section (x = r, z), y = 0
Point(1) = {a, 0, 0};
Point(2) = {c + delta, 0, 0};
Point(3) = {c + delta, 0, L};
Point(4) = {a, 0, L};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve {1, 3} = n + 1;
Transfinite Curve {2, 4} = n + 1;
Transfinite Surface {1} Alternate;

// outer tube section
Point(11) = {c, 0, 0};
Point(12) = {b, 0, 0};
Point(13) = {b, 0, L};
Point(14) = {c, 0, L};
Line(11) = {11, 12};
Line(12) = {12, 13};
Line(13) = {13, 14};
Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(2) = {2};
Transfinite Curve {11, 13} = n + 1;
Transfinite Curve {12, 14} = n + 2;
Transfinite Surface {2} Alternate;

// revolve: out[0] the end section, out[1] the volume, out[2..5] the faces
// swept by the section's curves (bottom, outer or bore side, top, ...)
nq = full ? 4 : 1;
si = 1; so = 2;
vi[] = {}; vo[] = {};
ib[] = {}; ic[] = {}; it[] = {}; ii[] = {};
ob[] = {}; os[] = {}; ot[] = {}; oc[] = {};
For q In {1:nq}
  ei[] = Extrude {{0, 0, 1}, {0, 0, 0}, Pi/2} { Surface{si}; Layers{N}; };
  eo[] = Extrude {{0, 0, 1}, {0, 0, 0}, Pi/2} { Surface{so}; Layers{N}; };
  vi[] += ei[1]; ib[] += ei[2]; ic[] += ei[3]; it[] += ei[4]; ii[] += ei[5];
  vo[] += eo[1]; ob[] += eo[2]; os[] += eo[3]; ot[] += eo[4]; oc[] += eo[5];
  si = ei[0]; so = eo[0];
EndFor

Physical Volume("inner") = {vi[]};
Physical Volume("outer") = {vo[]};
Physical Surface("inner_bottom") = {ib[]};
Physical Surface("inner_contact") = {ic[]};
Physical Surface("inner_top") = {it[]};
Physical Surface("inner_bore") = {ii[]};
Physical Surface("outer_bottom") = {ob[]};
Physical Surface("outer_surface") = {os[]};
Physical Surface("outer_top") = {ot[]};
Physical Surface("outer_contact") = {oc[]};
If (full == 0)
  Physical Surface("sym_y0") = {1, 2};
  Physical Surface("sym_x0") = {si, so};
Else
  e = 1e-6;
  For k In {0:3}
    x = Round(Cos(k * Pi / 2)); y = Round(Sin(k * Pi / 2));
    pi[] = Point In BoundingBox{a*x - e, a*y - e, -e, a*x + e, a*y + e, L + e};
    po[] = Point In BoundingBox{b*x - e, b*y - e, -e, b*x + e, b*y + e, L + e};
    Physical Point(Sprintf("in_%g", 90 * k)) = {pi[]};
    Physical Point(Sprintf("out_%g", 90 * k)) = {po[]};
  EndFor
EndIf
