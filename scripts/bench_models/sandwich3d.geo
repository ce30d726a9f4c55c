// A rubber cube between steel plates (scripts/bench_models/sandwich3d.toml).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2, 2, 0.5};
Box(2) = {0.5, 0.5, 0.5, 1, 1, 0.6};
Box(3) = {0.2, 0.2, 1.1, 1.6, 1.6, 0.4};
eps = 1e-6;
MeshSize{ PointsOf{ Volume{1}; } } = 0.09;
MeshSize{ PointsOf{ Volume{2}; } } = 0.05;
MeshSize{ PointsOf{ Volume{3}; } } = 0.07;
Physical Volume("base") = {1};
Physical Volume("cube") = {2};
Physical Volume("lid") = {3};
Physical Surface("base_bottom") = Surface In BoundingBox{-eps,-eps,-eps, 2+eps,2+eps,eps};
b() = Boundary{Volume{1};};
For i In {0:#b()-1}
  bb() = BoundingBox Surface{b(i)};
  If (Fabs(bb(2)-0.5) < eps && Fabs(bb(5)-0.5) < eps)
    Physical Surface("base_top") = {b(i)};
  EndIf
EndFor
Physical Surface("cube_bottom") = Surface In BoundingBox{0.5-eps,0.5-eps,0.5-eps, 1.5+eps,1.5+eps,0.5+eps};
Physical Surface("cube_top") = Surface In BoundingBox{0.5-eps,0.5-eps,1.1-eps, 1.5+eps,1.5+eps,1.1+eps};
c() = Boundary{Volume{3};};
For i In {0:#c()-1}
  bb() = BoundingBox Surface{c(i)};
  If (Fabs(bb(2)-1.1) < eps && Fabs(bb(5)-1.1) < eps)
    Physical Surface("lid_bottom") = {c(i)};
  EndIf
EndFor
Physical Surface("lid_top") = Surface In BoundingBox{0.2-eps,0.2-eps,1.5-eps, 1.8+eps,1.8+eps,1.5+eps};
