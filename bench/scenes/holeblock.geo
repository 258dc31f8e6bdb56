// SPDX-License-Identifier: BSD-3-Clause
// holeblock.geo -- non-convex benchmark domain (gmsh >= 4.8, OpenCASCADE kernel): an L-shaped
// 4 x 2 x 1 block with a cylindrical through-hole and a closed spherical void, cells graded
// from h/ratio next to those features up to h far from them.
SetFactory("OpenCASCADE");
If (!Exists(h))     h = 0.2;    EndIf   // far-field size
If (!Exists(ratio)) ratio = 20; EndIf   // grading: far size / near size
If (!Exists(band))  band = 0.8; EndIf   // distance over which size grows
Box(1) = {0, 0, 0, 4, 2, 1};
Box(2) = {2, 1, -0.1, 2.1, 1.1, 1.2};
Cylinder(3) = {1, 1, -0.1, 0, 0, 1.2, 0.3};
Sphere(4) = {3, 0.5, 0.5, 0.2};
BooleanDifference(10) = { Volume{1}; Delete; }{ Volume{2,3,4}; Delete; };
Physical Volume("solid", 1) = {10};   // only the tets are written out

Field[1] = MathEval; Field[1].F = "Sqrt((x-1)^2+(y-1)^2)-0.3";            // hole wall
Field[2] = MathEval; Field[2].F = "Sqrt((x-3)^2+(y-0.5)^2+(z-0.5)^2)-0.2"; // void wall
Field[3] = MathEval; Field[3].F = "Sqrt((x-2)^2+(y-1)^2)";                // re-entrant edge
Field[4] = Min; Field[4].FieldsList = {1, 2, 3};
Field[5] = Threshold; Field[5].InField = 4;
Field[5].SizeMin = h / ratio; Field[5].SizeMax = h;
Field[5].DistMin = 0.02;      Field[5].DistMax = band;
Background Field = 5;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
