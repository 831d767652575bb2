// cases/README.md §A wall written by hand in Gmsh's .geo language: 1000 x 1000 mm, 200 x 100 mm units, running bond
// (courses of 5 full units alternate with 4 full and 2 half units), dry joints, 50 mm mesh. Group names follow
// mesh/wall.hpp so that tests can compare it with the generated wall.
SetFactory("OpenCASCADE");
L = 1.0; ul = 0.2; uh = 0.1; h = 0.05; e = 1e-6;
n = 0;
For c In {0:9}
  If (c % 2 == 0)
    For k In {0:4}
      n++; Rectangle(n) = {k * ul, c * uh, 0, ul, uh};
    EndFor
  Else
    n++; Rectangle(n) = {0, c * uh, 0, ul / 2, uh};
    For k In {0:3}
      n++; Rectangle(n) = {ul / 2 + k * ul, c * uh, 0, ul, uh};
    EndFor
    n++; Rectangle(n) = {L - ul / 2, c * uh, 0, ul / 2, uh};
  EndIf
EndFor
BooleanFragments{ Surface{1:n}; Delete; }{}
MeshSize{ PointsOf{ Surface{:}; } } = h;
Physical Surface("units") = Surface{:};
Physical Curve("wall_bottom") = Curve In BoundingBox{-e, -e, -e, L + e, e, e};
Physical Curve("wall_top") = Curve In BoundingBox{-e, 1 - e, -e, L + e, 1 + e, e};
Physical Curve("wall_left") = Curve In BoundingBox{-e, -e, -e, e, 1 + e, e};
Physical Curve("wall_right") = Curve In BoundingBox{L - e, -e, -e, L + e, 1 + e, e};
Physical Point("toe_left") = Point In BoundingBox{-e, -e, -e, e, e, e};
Physical Point("toe_right") = Point In BoundingBox{L - e, -e, -e, L + e, e, e};
