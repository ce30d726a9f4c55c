// geodynamic.geo -- schematic subduction-zone model after the report's 6.4
// (GENERATED coordinates, see meshes/README.md). Units: metres (km * 1e3).
// Domain x in [0, 700] km, y in [-150, 0] km. Three bodies:
//   body "continental plate" (left, overriding): 4 subregions,
//   body "oceanic plate + slab" (right, subducting at 30 deg): 3 subregions,
//   body "sublithospheric mantle" (below): 3 subregions.
// Faults (conforming contact, each a chain of lines shared by two bodies):
//   fault_subduction  continental plate / slab (subduction interface, trench at x = 400 km),
//   fault_cont_base   base of the continental plate / mantle (y = -60 km),
//   fault_ocean_base  base of the oceanic plate and slab / mantle.
// Extra points (probes): (150, 0), (550, 0) on the surface, (350, -130) km
// embedded in the lower asthenosphere.
// The three faults meet at the triple junction T = (296.08, -60) km.
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

km = 1000.0;

Point(1) = {0.0000*km, 0.0000*km, 0, 8.0*km};  // W1
Point(2) = {150.0000*km, 0.0000*km, 0, 8.0*km};  // C150
Point(3) = {550.0000*km, 0.0000*km, 0, 8.0*km};  // O550
Point(4) = {350.0000*km, -130.0000*km, 0, 12.0*km};  // P130
Point(5) = {350.0000*km, 0.0000*km, 0, 5.0*km};  // Aw
Point(6) = {400.0000*km, 0.0000*km, 0, 5.0*km};  // Tr
Point(7) = {700.0000*km, 0.0000*km, 0, 8.0*km};  // E1
Point(8) = {0.0000*km, -15.0000*km, 0, 8.0*km};  // L15
Point(9) = {0.0000*km, -35.0000*km, 0, 8.0*km};  // L35
Point(10) = {0.0000*km, -60.0000*km, 0, 8.0*km};  // W0
Point(11) = {0.0000*km, -110.0000*km, 0, 12.0*km};  // L110
Point(12) = {0.0000*km, -150.0000*km, 0, 12.0*km};  // L150
Point(13) = {700.0000*km, -8.0000*km, 0, 8.0*km};  // E8
Point(14) = {700.0000*km, -60.0000*km, 0, 8.0*km};  // E2
Point(15) = {700.0000*km, -110.0000*km, 0, 12.0*km};  // R110
Point(16) = {700.0000*km, -150.0000*km, 0, 12.0*km};  // R150
Point(17) = {296.0770*km, -60.0000*km, 0, 5.0*km};  // T
Point(18) = {261.4359*km, -80.0000*km, 0, 5.0*km};  // St
Point(19) = {276.4359*km, -105.9808*km, 0, 5.0*km};  // Sb
Point(20) = {356.0770*km, -60.0000*km, 0, 5.0*km};  // Bb
Point(21) = {402.1436*km, -8.0000*km, 0, 5.0*km};  // K
Point(22) = {265.4359*km, -86.9282*km, 0, 5.0*km};  // Ct
Point(23) = {374.0192*km, -15.0000*km, 0, 5.0*km};  // F15
Point(24) = {339.3782*km, -35.0000*km, 0, 5.0*km};  // F35
Point(25) = {230.0000*km, -60.0000*km, 0, 5.0*km};  // M

Line(1) = {5, 23};  // Aw - F15
Line(2) = {23, 6};  // F15 - Tr
Line(3) = {6, 5};  // Tr - Aw
Line(4) = {1, 8};  // W1 - L15
Line(5) = {8, 23};  // L15 - F15
Line(6) = {5, 2};  // Aw - C150
Line(7) = {2, 1};  // C150 - W1
Line(8) = {8, 9};  // L15 - L35
Line(9) = {9, 24};  // L35 - F35
Line(10) = {24, 23};  // F35 - F15
Line(11) = {9, 10};  // L35 - W0
Line(12) = {10, 25};  // W0 - M
Line(13) = {25, 17};  // M - T
Line(14) = {17, 24};  // T - F35
Line(15) = {17, 18};  // T - St
Line(16) = {18, 22};  // St - Ct
Line(17) = {22, 21};  // Ct - K
Line(18) = {21, 13};  // K - E8
Line(19) = {13, 7};  // E8 - E1
Line(20) = {7, 3};  // E1 - O550
Line(21) = {3, 6};  // O550 - Tr
Line(22) = {21, 20};  // K - Bb
Line(23) = {20, 14};  // Bb - E2
Line(24) = {14, 13};  // E2 - E8
Line(25) = {22, 19};  // Ct - Sb
Line(26) = {19, 20};  // Sb - Bb
Line(27) = {25, 18};  // M - St
Line(28) = {10, 11};  // W0 - L110
Line(29) = {11, 15};  // L110 - R110
Line(30) = {15, 14};  // R110 - E2
Line(31) = {11, 12};  // L110 - L150
Line(32) = {12, 16};  // L150 - R150
Line(33) = {16, 15};  // R150 - R110

Curve Loop(1) = {1, 2, 3};
Plane Surface(1) = {1};  // accretionary_wedge
Curve Loop(2) = {4, 5, -1, 6, 7};
Plane Surface(2) = {2};  // cont_upper_crust
Curve Loop(3) = {8, 9, 10, -5};
Plane Surface(3) = {3};  // cont_lower_crust
Curve Loop(4) = {11, 12, 13, 14, -9};
Plane Surface(4) = {4};  // cont_mantle_lith
Curve Loop(5) = {-2, -10, -14, 15, 16, 17, 18, 19, 20, 21};
Plane Surface(5) = {5};  // ocean_crust
Curve Loop(6) = {-18, 22, 23, 24};
Plane Surface(6) = {6};  // ocean_mantle_lith
Curve Loop(7) = {-17, 25, 26, -22};
Plane Surface(7) = {7};  // slab_mantle
Curve Loop(8) = {27, -15, -13};
Plane Surface(8) = {8};  // mantle_wedge
Curve Loop(9) = {28, 29, 30, -23, -26, -25, -16, -27, -12};
Plane Surface(9) = {9};  // asthenosphere_upper
Curve Loop(10) = {31, 32, 33, -29};
Plane Surface(10) = {10};  // asthenosphere_lower

Point{4} In Surface{10};  // probe point P130

Physical Surface("accretionary_wedge") = {1};
Physical Surface("cont_upper_crust") = {2};
Physical Surface("cont_lower_crust") = {3};
Physical Surface("cont_mantle_lith") = {4};
Physical Surface("ocean_crust") = {5};
Physical Surface("ocean_mantle_lith") = {6};
Physical Surface("slab_mantle") = {7};
Physical Surface("mantle_wedge") = {8};
Physical Surface("asthenosphere_upper") = {9};
Physical Surface("asthenosphere_lower") = {10};
Physical Curve("surface") = {7, 6, 3, 21, 20};
Physical Curve("left_plate") = {4, 8, 11};
Physical Curve("right_plate") = {19, 24};
Physical Curve("mantle_left") = {28, 31};
Physical Curve("mantle_right") = {30, 33};
Physical Curve("base") = {32};
Physical Curve("fault_cont_base") = {13, 12};
Physical Curve("fault_subduction") = {2, 10, 14};
Physical Curve("fault_ocean_base") = {15, 16, 25, 26, 23};
