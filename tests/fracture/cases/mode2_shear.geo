// Two blocks L x H (m), one on top of the other, meshed as structured grids that share the line y = 0 (the bonded
// interface of mode2_shear.toml: nx cohesive elements of length L / nx). Next to the interface each block has a thin
// strip of one row of triangles (height s): the supports of the case hold everything but the interface nodes, and
// the thin, stiff strip passes the shear on with a lag (tau s / G) small against the joint's slip and the same
// along the joint, and a lever arm (2 s) too short for a moment to make the normal stress uneven.
L = 0.1; H = 0.05; s = 0.002; nx = 10; ny = 4;
Point(1) = {0, -H, 0}; Point(2) = {L, -H, 0}; Point(3) = {L, -s, 0}; Point(4) = {0, -s, 0};
Point(5) = {L, 0, 0}; Point(6) = {0, 0, 0}; Point(7) = {L, s, 0}; Point(8) = {0, s, 0};
Point(9) = {L, H, 0}; Point(10) = {0, H, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};   // lower body
Line(5) = {3, 5}; Line(6) = {5, 6}; Line(7) = {6, 4};                     // lower strip (6: the interface)
Line(8) = {5, 7}; Line(9) = {7, 8}; Line(10) = {8, 6};                    // upper strip
Line(11) = {7, 9}; Line(12) = {9, 10}; Line(13) = {10, 8};                // upper body
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7}; Plane Surface(2) = {2};
Curve Loop(3) = {-6, 8, 9, 10}; Plane Surface(3) = {3};
Curve Loop(4) = {-9, 11, 12, 13}; Plane Surface(4) = {4};
Transfinite Curve{1, 3, 6, 9, 12} = nx + 1;
Transfinite Curve{2, 4, 11, 13} = ny + 1; Transfinite Curve{5, 7, 8, 10} = 2;
Transfinite Surface{1}; Transfinite Surface{2}; Transfinite Surface{3}; Transfinite Surface{4};
Physical Surface("lower") = {1, 2}; Physical Surface("upper") = {3, 4};
Physical Curve("upper_top") = {12}; Physical Curve("lower_bottom") = {1};
