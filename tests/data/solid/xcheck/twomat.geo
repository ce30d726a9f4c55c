SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1.0, 0.8, 0.5};
Box(2) = {0, 0, 0.5, 1.0, 0.8, 0.3};
Cylinder(3) = {0.5, 0.4, 0.5, 0, 0, 0.3, 0.2};
BooleanFragments{ Volume{1,2,3}; Delete; }{}
Mesh.CharacteristicLengthMax = 0.09;
eps = 1e-6;
Physical Volume("steel") = Volume In BoundingBox{-eps,-eps,-eps, 1+eps,0.8+eps,0.5+eps};
Physical Volume("rubber") = {3};
Physical Volume("cover") = {4};
Physical Surface("sym_x") = Surface In BoundingBox{-eps,-eps,-eps, eps,0.8+eps,0.8+eps};
Physical Surface("sym_y") = Surface In BoundingBox{-eps,-eps,-eps, 1+eps,eps,0.8+eps};
Physical Surface("base") = Surface In BoundingBox{-eps,-eps,-eps, 1+eps,0.8+eps,eps};
Physical Surface("top") = Surface In BoundingBox{-eps,-eps,0.8-eps, 1+eps,0.8+eps,0.8+eps};
Physical Surface("side") = Surface In BoundingBox{1-eps,-eps,-eps, 1+eps,0.8+eps,0.8+eps};
