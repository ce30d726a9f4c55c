// A cylinder on a block in 3D, plane strain by slip planes at y = 0 and
// y = L: Hertz line contact (docs/verification.md, "Cylinder on a block").
// Half model (x >= 0); the cylinder is cut at its axis height and the flat
// cut is loaded by a pressure; uniform tetrahedra of size hf.
SetFactory("OpenCASCADE");
R = 0.05; L = 0.01; W = 0.06; H = 0.06;
If (!Exists(hf)) hf = 0.0015; EndIf
Box(1) = {0, 0, -H, W, L, H};
Cylinder(2) = {0, 0, R, 0, L, 0, R};
Box(3) = {0, 0, 0, R, L, R};
BooleanIntersection(4) = { Volume{2}; Delete; }{ Volume{3}; Delete; };
eps = 1e-6;
Physical Volume("block") = {1};
Physical Volume("cyl") = {4};
cx0[] = Surface In BoundingBox{-eps, -eps, -H-eps, eps, L+eps, R+eps};
cy0[] = Surface In BoundingBox{-eps, -eps, -H-eps, W+eps, eps, R+eps};
cy1[] = Surface In BoundingBox{-eps, L-eps, -H-eps, W+eps, L+eps, R+eps};
Physical Surface("x0") = {cx0[]};
Physical Surface("y0") = {cy0[]};
Physical Surface("y1") = {cy1[]};
Physical Surface("block_bottom") = Surface In BoundingBox{-eps, -eps, -H-eps, W+eps, L+eps, -H+eps};
Physical Surface("block_top") = Surface In BoundingBox{-eps, -eps, -eps, W+eps, L+eps, eps};
Physical Surface("cyl_top") = Surface In BoundingBox{-eps, -eps, R-eps, R+eps, L+eps, R+eps};
all4[] = Boundary{ Volume{4}; };
curved[] = {};
For i In {0:#all4[]-1}
  s = Abs(all4[i]);
  bb[] = BoundingBox Surface{s};
  If (bb[3]-bb[0] > 0.5*R && bb[5]-bb[2] > 0.5*R && bb[4]-bb[1] > 0.5*L)
    curved[] += s;
  EndIf
EndFor
Physical Surface("cyl_surf") = {curved[]};
Mesh.CharacteristicLengthMax = hf;
Mesh.CharacteristicLengthFromCurvature = 0;
