// Brazilian disc of brazilian_disc.toml: radius R, load arcs of +-a about the vertical, mesh size lc (m).
R = 0.05; a = 6 * Pi / 180; lc = 0.0075;
Point(1) = {0, 0, 0, lc};
Point(2) = {R*Sin(a), R*Cos(a), 0, lc}; Point(3) = {-R*Sin(a), R*Cos(a), 0, lc};
Point(4) = {-R*Sin(a), -R*Cos(a), 0, lc}; Point(5) = {R*Sin(a), -R*Cos(a), 0, lc};
Circle(1) = {2, 1, 3}; Circle(2) = {3, 1, 4}; Circle(3) = {4, 1, 5}; Circle(4) = {5, 1, 2};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Physical Curve("top") = {1}; Physical Curve("bottom") = {3};
Physical Surface("body") = {1};
