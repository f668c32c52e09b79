#!/usr/bin/env bash
# Seeds fuzz/corpus/<target>/ from the real meshes in ../shared/data/meshes (where present),
# the scenes in data/scenes, files perifrac's own writers make, and the reproducers of
# issue 17. Existing corpus files (what earlier runs found) are kept.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
corpus=$root/fuzz/corpus
shared=$root/../shared/data/meshes
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cargo build -q -p perifrac
perifrac=$root/target/debug/perifrac
for t in read_medit read_gmsh read_vtk read_tetgen read_obj read_off read_ply scene mesh_spec; do
    mkdir -p "$corpus/$t"
done

# Tet meshes: a small box, and the octopus when ../shared is here, in every format we write.
"$perifrac" mesh box:1x0.5x0.25 --cells 2,2,1 -o "$work/box.mesh" 2>/dev/null
meshes=("$work/box.mesh")
if [ -f "$shared/octopus-low.mesh" ]; then
    cp "$shared/octopus-low.mesh" "$work/octopus.mesh"
    meshes+=("$work/octopus.mesh")
fi
for m in "${meshes[@]}"; do
    b=$(basename "$m" .mesh)
    cp "$m" "$corpus/read_medit/$b.mesh"
    "$perifrac" convert "$m" "$work/$b.msh" >/dev/null 2>&1
    "$perifrac" convert --gmsh22 "$m" "$work/${b}22.msh" >/dev/null 2>&1
    cp "$work/$b.msh" "$work/${b}22.msh" "$corpus/read_gmsh/"
    "$perifrac" convert "$m" "$work/$b.vtk" >/dev/null 2>&1
    cp "$work/$b.vtk" "$corpus/read_vtk/"
    "$perifrac" convert "$m" "$work/$b.node" >/dev/null 2>&1
    # The TetGen target splits its input at NUL bytes into .node, .ele and .face.
    {
        cat "$work/$b.node"; printf '\0'; cat "$work/$b.ele"
        if [ -f "$work/$b.face" ]; then printf '\0'; cat "$work/$b.face"; fi
    } > "$corpus/read_tetgen/$b.tetgen"
done

# Surfaces: the smaller real ones as they are (the large ones are cut by libFuzzer's
# -max_len anyway), and a box surface in each format we write.
for s in woody.obj spot.obj bunny.off; do
    if [ -f "$shared/$s" ]; then
        case $s in *.obj) t=read_obj ;; *.off) t=read_off ;; esac
        cp "$shared/$s" "$corpus/$t/$s"
    fi
done
if [ -f "$shared/woody.obj" ]; then
    "$perifrac" convert "$shared/woody.obj" "$work/woody.ply" >/dev/null 2>&1
    cp "$work/woody.ply" "$corpus/read_ply/woody-binary.ply"
fi
cat > "$corpus/read_obj/quad.obj" <<'OBJ'
# two triangles and a quad, with normals and texture coordinates
mtllib none.mtl
o quad
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vn 0 0 1
f 1/1/1 2/1/1 3/1/1 4/1/1
f -4 -3 -2
OBJ
cat > "$corpus/read_off/tet.off" <<'END_OFF'
OFF
# a tetrahedron
4 4 6
0 0 0
1 0 0
0 1 0
0 0 1
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
END_OFF
cat > "$corpus/read_ply/tet-ascii.ply" <<'PLY'
ply
format ascii 1.0
comment a tetrahedron with crack flags and a particle scalar
element vertex 4
property float x
property float y
property float z
property float damage
element face 4
property list uchar int vertex_indices
property uchar crack
end_header
0 0 0 0
1 0 0 0.5
0 1 0 1
0 0 1 0
3 0 2 1 0
3 0 1 3 1
3 0 3 2 0
4 1 2 3 1 0
PLY

# Scenes: every scene in data/scenes (their mesh files, if any, are not found from the
# fuzzer's directory: those inputs test the error path), and each cut to a few cells so that
# its setup runs to the end and steps within the target's budgets.
cp data/scenes/*.toml "$corpus/scene/"
for s in data/scenes/*.toml; do
    sed -E 's/^cells = \[[^]]*\]/cells = [4, 4, 2]/; s/^resolution = [0-9]+/resolution = 4/' \
        "$s" > "$corpus/scene/small_$(basename "$s")"
done

# Primitive specs (first line) and cells or resolution (second line), with the reproducers
# that panicked or aborted before issue 17.
i=0
while IFS= read -r line; do
    i=$((i + 1))
    printf '%b' "$line" > "$corpus/mesh_spec/spec$i"
done <<'SPECS'
box:1x0.2x0.5\n8
bar:1x0.1x0.1\n4,1,1
sphere:0.5\n6
cylinder:0.2x1\n5
box:1e8x1x1\n20
box:1e-30x1x1\n20
box:1e308x1x1\n20
bar:1e308x1x1\n20
box:1x1x1\n4294967296,4294967296,1
box:1x1x1\n9223372036854775808,2,1
SPECS
for t in "$corpus"/*; do
    echo "$(basename "$t"): $(ls "$t" | wc -l) inputs"
done
