SetFactory("OpenCASCADE");
// Quarter model: a steel flat punch (radius 0.3) on an aluminium block.
Box(1) = {0, 0, 0, 1.0, 1.0, 0.5};
Cylinder(2) = {0, 0, 0.5, 0, 0, 0.3, 0.3, Pi/2};
eps = 1e-6;
Mesh.CharacteristicLengthMax = 0.1;
Field[1] = Ball; Field[1].Radius = 0.45; Field[1].XCenter = 0; Field[1].YCenter = 0; Field[1].ZCenter = 0.5;
Field[1].VIn = 0.03; Field[1].VOut = 0.1; Field[1].Thickness = 0.3;
Background Field = 1;
Physical Volume("block") = {1};
Physical Volume("punch") = {2};
Physical Surface("block_top") = {6};
Physical Surface("punch_bottom") = Surface In BoundingBox{-eps,-eps,0.5-eps, 0.3+eps,0.3+eps,0.5+eps};
Physical Surface("punch_top") = Surface In BoundingBox{-eps,-eps,0.8-eps, 0.3+eps,0.3+eps,0.8+eps};
Physical Surface("base") = Surface In BoundingBox{-eps,-eps,-eps, 1+eps,1+eps,eps};
Physical Surface("sym_x") = Surface In BoundingBox{-eps,-eps,-eps, eps,1+eps,0.8+eps};
Physical Surface("sym_y") = Surface In BoundingBox{-eps,-eps,-eps, 1+eps,eps,0.8+eps};
