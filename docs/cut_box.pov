// Renders examples/cut_box.rs's output with Debian's POV-Ray:
//   cargo run --release --example cut_box
//   povray +W640 +H400 +A0.3 -D +L. +Odocs/cut_box.png docs/cut_box.pov
// (run from the repository root). perifrac is z-up and right-handed; POV-Ray is y-up and
// left-handed, so the object swaps y and z (a reflection, which also fixes the handedness).
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "out/cut_box/cut_box.inc"
camera { location <1.6, 1.3, -1.2> look_at <0.5, 0.2, 0.25> angle 45 }
light_source { <3, 5, -4> color rgb 1 }
light_source { <-2, 3, -3> color rgb 0.4 }
background { color rgb <0.95, 0.96, 1.0> }
plane { y, 0 pigment { checker rgb 0.8 rgb 0.65 scale 0.25 } }
object { cut_box matrix <1,0,0, 0,0,1, 0,1,0, 0,0,0> }
