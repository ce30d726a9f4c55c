// sneddon_3d.geo -- Sneddon's rigid flat cylindrical punch on a half-space
// in 3D: a quarter of sneddon.geo's model revolved (slip planes x = 0 and
// y = 0). Units m. Punch: radius a = 0.1, height 0.1, on top of the block
// z = 0; block: a quarter cylinder of radius R = H = 200 a, base z = -H
// fixed. The punch base is one face of both volumes (BooleanFragments):
// conforming rows. Element size hc at the punch base growing as hc + k d
// (d the distance from it), as sneddon.geo with k set by scripts/verify.
SetFactory("OpenCASCADE");
DefineConstant[ hc = {0.01, Name "hc"}, k = {0.1, Name "k"} ];
a = 0.1; hp = 0.1; R = 20.0; H = 20.0;
Cylinder(1) = {0, 0, -H, 0, 0, H, R, Pi/2};    // block
Cylinder(2) = {0, 0, 0, 0, 0, hp, a, Pi/2};    // punch
BooleanFragments{ Volume{1, 2}; Delete; }{}
e = 1e-6;
base() = Surface In BoundingBox{-e, -e, -e, a+e, a+e, e};
ptop() = Surface In BoundingBox{-e, -e, hp-e, a+e, a+e, hp+e};
bot() = Surface In BoundingBox{-e, -e, -H-e, R+e, R+e, -H+e};
sx() = Surface In BoundingBox{-e, -e, -H-e, e, R+e, hp+e};
sy() = Surface In BoundingBox{-e, -e, -H-e, R+e, e, hp+e};
pv() = Volume In BoundingBox{-e, -e, -e, a+e, a+e, hp+e};
bv() = Volume In BoundingBox{-e, -e, -H-e, R+e, R+e, e};

Field[1] = Distance;
Field[1].SurfacesList = {base()};
Field[2] = MathEval;
Field[2].F = Sprintf("%g + %g*F1", hc, k);
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Volume("punch") = {pv()};
Physical Volume("block") = {bv()};
Physical Surface("punch_base") = {base()};
Physical Surface("punch_top") = {ptop()};
Physical Surface("block_bottom") = {bot()};
Physical Surface("sym_x") = {sx()};
Physical Surface("sym_y") = {sy()};
