// The cracked egg of examples/shell_egg.rs, seen from under the (glass) ground where it landed,
// crack walls in red.
// povray +Idocs/shell_egg.pov +Odocs/shell_egg.png +W800 +H600 +A Declare=Frame=10
// (run from a directory holding out/shell_egg, or change the include path)
#version 3.7;
global_settings { assumed_gamma 1.0 }
#ifndef (Frame) #declare Frame = 10; #end
#declare egg_surface_texture = texture { pigment { rgb <0.93, 0.86, 0.74> } finish { diffuse 0.8 specular 0.2 } }
#declare egg_crack_texture = texture { pigment { rgb <0.75, 0.12, 0.08> } finish { diffuse 0.9 } }
#include concat("out/shell_egg/egg_", str(Frame, -4, 0), ".inc")
camera { location <0.05, -0.07, -0.06> look_at <0, 0, 0.012> angle 45 }
light_source { <0.3, -0.2, -0.4> color rgb 1.0 }
light_source { <-0.3, -0.4, 0.3> color rgb 0.5 }
background { rgb <0.95, 0.95, 0.97> }
plane { z, 0 pigment { checker rgbf <0.75, 0.75, 0.78, 0.85> rgbf <0.85, 0.85, 0.88, 0.9> scale 0.01 } }
object { egg }
