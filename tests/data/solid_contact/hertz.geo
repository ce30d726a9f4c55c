// Hertz (issue 45, tests/solid_contact.rs, docs/verification.md): a
// quarter of the lower half of a sphere of radius R = 1 (centre (0, 0, 1))
// resting at the origin on a quarter block [0, 1] x [0, 1] x [-1, 0].
// The two bodies are meshed apart (they touch at one point): slave "ball"
// (the spherical surface), master "block_top" (z = 0). Slip on x = 0 and
// y = 0 (both bodies) and on the block's bottom; a pressure on "ball_top"
// (z = 1). The mesh is refined to hc within 0.2 of the origin. hertz.msh is
// hc = 0.02; hertz_coarse.msh (tests/nested_start.rs) hc = 0.045.
SetFactory("OpenCASCADE");
DefineConstant[ hc = 0.02, hf = 0.25 ];
Sphere(1) = {0, 0, 1, 1};
Box(2) = {0, 0, 0, 1, 1, 1};
BooleanIntersection(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Box(4) = {0, 0, -1, 1, 1, 1};
e = 1e-6;
Physical Volume("ball") = {3};
Physical Volume("block") = {4};
Physical Surface("ball_top") = Surface In BoundingBox{-e, -e, 1 - e, 1 + e, 1 + e, 1 + e};
// The spherical surface: the ball's boundary without its planes.
ball() = Abs(Boundary{ Volume{3}; });
ball() -= Surface In BoundingBox{-e, -e, -e, e, 1 + e, 1 + e};
ball() -= Surface In BoundingBox{-e, -e, -e, 1 + e, e, 1 + e};
ball() -= Surface In BoundingBox{-e, -e, 1 - e, 1 + e, 1 + e, 1 + e};
Physical Surface("ball") = ball();
Physical Surface("block_top") = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, e};
Physical Surface("x0") = Surface In BoundingBox{-e, -e, -1 - e, e, 1 + e, 1 + e};
Physical Surface("y0") = Surface In BoundingBox{-e, -e, -1 - e, 1 + e, e, 1 + e};
Physical Surface("block_bottom") = Surface In BoundingBox{-e, -e, -1 - e, 1 + e, 1 + e, -1 + e};
Field[2] = MathEval;
Field[2].F = Sprintf("%g + %g * Max(0, Sqrt(x*x + y*y + z*z) - 0.2)", hc, 0.5);
Background Field = 2;
Mesh.MeshSizeMax = hf;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
