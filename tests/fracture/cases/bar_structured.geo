// Bar 0.2 x 0.1 m (cases/README.md §A2 stone unit) meshed as nx x ny cells split by alternating diagonals, so that every
// column boundary is a straight vertical line of edges: a mode I crack can run straight across the bar.
// Used by bar_structured.toml; change nx, ny (keep nx = 2 ny) for the mesh sizes 50, 25, 12.5, 10 mm (4, 8, 16, 20).
nx = 16; ny = 8;
Point(1) = {0, 0, 0}; Point(2) = {0.2, 0, 0}; Point(3) = {0.2, 0.1, 0}; Point(4) = {0, 0.1, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 3} = nx + 1; Transfinite Curve{2, 4} = ny + 1;
Transfinite Surface{1} Alternate;
Physical Curve("left") = {4}; Physical Curve("right") = {2};
Physical Surface("body") = {1};
