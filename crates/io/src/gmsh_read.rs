//! Gmsh `.msh` reader, ASCII versions 2.2 and 4.1 (detected from `$MeshFormat`).
//!
//! Tets (type 4) become `tets`; the label is the physical tag (2.2, first tag) or the entity
//! tag (4.1). Triangles (type 2) become `boundary_faces`; other element types are counted in
//! `skipped`. Node tags may be non-contiguous and are mapped to 0-based indices. Unknown
//! sections (`$Entities`, `$PhysicalNames`, ...) are skipped. Binary files are refused.

use crate::check::{self, Skipped};
use crate::error::read_all;
use crate::tokens::{show, Tokens};
use crate::{IoError, TetMeshData};
use std::collections::HashMap;
use std::path::Path;

/// Reads a `.msh` file.
pub(crate) fn read(path: &Path) -> Result<TetMeshData, IoError> {
    parse(path, &read_all(path)?)
}

/// Parses the bytes of a `.msh` file.
pub(crate) fn parse(path: &Path, data: &[u8]) -> Result<TetMeshData, IoError> {
    let mut t = Tokens::new(path, data);
    t.set_comments(false);
    expect_word(&mut t, "$MeshFormat")?;
    let version = t.expect("a version number after \"$MeshFormat\"")?;
    let major = match version {
        b"2" | b"2.0" | b"2.1" | b"2.2" => 2,
        b"4.1" => 4,
        _ => {
            return Err(IoError::Unsupported {
                file: path.to_path_buf(),
                what: format!(
                    "Gmsh format version {}; save as 4.1 or 2.2 (ASCII)",
                    show(version)
                ),
            })
        }
    };
    let file_type = t.u64("the file type (0 = ASCII)")?;
    if file_type != 0 {
        return Err(IoError::Unsupported {
            file: path.to_path_buf(),
            what: "binary Gmsh file; save it as ASCII (gmsh option Mesh.Binary = 0)".into(),
        });
    }
    t.u64("the data size")?;
    expect_word(&mut t, "$EndMeshFormat")?;
    let mut mesh = TetMeshData::default();
    let mut skipped = Skipped::default();
    let mut nodes: Option<NodeMap> = None;
    while let Some(section) = t.next() {
        match section {
            b"$Nodes" if nodes.is_some() => return Err(t.error("a second \"$Nodes\" section")),
            b"$Nodes" => {
                let (map, coords) = if major == 2 {
                    nodes_v2(&mut t)?
                } else {
                    nodes_v4(&mut t)?
                };
                mesh.vertices = coords;
                nodes = Some(map);
            }
            b"$Elements" => {
                let Some(map) = &nodes else {
                    return Err(t.error("\"$Elements\" before \"$Nodes\""));
                };
                if major == 2 {
                    elements_v2(&mut t, map, &mut mesh, &mut skipped)?;
                } else {
                    elements_v4(&mut t, map, &mut mesh, &mut skipped)?;
                }
            }
            other if other.starts_with(b"$") && !other.starts_with(b"$End") => {
                let mut end = b"$End".to_vec();
                end.extend_from_slice(other.get(1..).unwrap_or(&[]));
                let what = format!("\"{}\"", show(&end));
                while t.expect(&what)? != end.as_slice() {}
            }
            other => {
                return Err(t.unexpected("a section such as \"$Nodes\" or \"$Elements\"", other))
            }
        }
    }
    mesh.skipped = skipped.into_vec();
    Ok(mesh)
}

fn expect_word(t: &mut Tokens, word: &str) -> Result<(), IoError> {
    let what = format!("\"{word}\"");
    let found = t.expect(&what)?;
    if found == word.as_bytes() {
        Ok(())
    } else {
        Err(t.unexpected(&what, found))
    }
}

/// Node tag -> 0-based index, dense when tags are compact, hashed otherwise.
enum NodeMap {
    Dense(Vec<u32>),
    Sparse(HashMap<u64, u32>),
}

impl NodeMap {
    /// Builds the map; `section_line` is reported for a duplicate tag.
    fn new(t: &Tokens, tags: &[u64], section_line: usize) -> Result<NodeMap, IoError> {
        let max = tags.iter().copied().max().unwrap_or(0);
        let duplicate =
            |tag: u64| t.error_at(section_line, format!("node tag {tag} appears twice"));
        if max <= 4 * tags.len() as u64 + 1024 {
            let mut dense = vec![u32::MAX; max as usize + 1];
            for (i, &tag) in tags.iter().enumerate() {
                match dense.get_mut(tag as usize) {
                    Some(slot) if *slot == u32::MAX => *slot = i as u32,
                    _ => return Err(duplicate(tag)),
                }
            }
            Ok(NodeMap::Dense(dense))
        } else {
            let mut sparse = HashMap::with_capacity(tags.len());
            for (i, &tag) in tags.iter().enumerate() {
                if sparse.insert(tag, i as u32).is_some() {
                    return Err(duplicate(tag));
                }
            }
            Ok(NodeMap::Sparse(sparse))
        }
    }

    fn get(&self, tag: u64) -> Option<u32> {
        match self {
            NodeMap::Dense(d) => d.get(tag as usize).copied().filter(|&i| i != u32::MAX),
            NodeMap::Sparse(s) => s.get(&tag).copied(),
        }
    }
}

fn nodes_v2(t: &mut Tokens) -> Result<(NodeMap, Vec<[f64; 3]>), IoError> {
    let section_line = t.line();
    let n = t.usize("the number of nodes after \"$Nodes\"")?;
    check_u32(t, n, "nodes")?;
    let mut tags = Vec::with_capacity(t.capacity_hint(n, 8));
    let mut coords = Vec::with_capacity(t.capacity_hint(n, 8));
    for i in 0..n {
        let ctx = || format!("node {} of {n}", i + 1);
        tags.push(t.u64("a node tag").map_err(|e| e.context(ctx))?);
        let mut p = [0.0; 3];
        for c in &mut p {
            *c = t.f64("coordinate").map_err(|e| e.context(ctx))?;
        }
        coords.push(p);
    }
    expect_word(t, "$EndNodes")?;
    Ok((NodeMap::new(t, &tags, section_line)?, coords))
}

fn nodes_v4(t: &mut Tokens) -> Result<(NodeMap, Vec<[f64; 3]>), IoError> {
    let section_line = t.line();
    let blocks = t.usize("the number of entity blocks after \"$Nodes\"")?;
    let n = t.usize("the number of nodes")?;
    check_u32(t, n, "nodes")?;
    t.u64("the minimum node tag")?;
    t.u64("the maximum node tag")?;
    let mut tags = Vec::with_capacity(t.capacity_hint(n, 8));
    let mut coords = Vec::with_capacity(t.capacity_hint(n, 8));
    for _ in 0..blocks {
        let dim = t.usize("an entity dimension (node block header)")?;
        t.i64("an entity tag")?;
        let parametric = t.u64("the parametric flag")?;
        let count = t.usize("the number of nodes in the block")?;
        if tags.len().saturating_add(count) > n {
            return Err(t.error(format!(
                "node blocks hold more than the {n} nodes announced"
            )));
        }
        for _ in 0..count {
            tags.push(t.u64("a node tag")?);
        }
        let params = if parametric == 1 { dim.min(3) } else { 0 };
        for _ in 0..count {
            let mut p = [0.0; 3];
            for c in &mut p {
                *c = t.f64("coordinate")?;
            }
            for _ in 0..params {
                t.f64("a parametric coordinate")?;
            }
            coords.push(p);
        }
    }
    if tags.len() != n {
        return Err(t.error(format!(
            "node blocks hold {} nodes, the header announced {n}",
            tags.len()
        )));
    }
    expect_word(t, "$EndNodes")?;
    Ok((NodeMap::new(t, &tags, section_line)?, coords))
}

fn check_u32(t: &Tokens, n: usize, what: &str) -> Result<(), IoError> {
    if n > u32::MAX as usize {
        return Err(t.error(format!(
            "{n} {what} is more than this reader supports (2^32 - 1)"
        )));
    }
    Ok(())
}

/// Maps node tags to indices; errors name the element and line.
fn lookup<const N: usize>(
    t: &mut Tokens,
    map: &NodeMap,
    kind: &str,
    id: u64,
) -> Result<[u32; N], IoError> {
    let mut raw = [0u64; N];
    for r in &mut raw {
        *r = t.u64("a node tag of the element")?;
    }
    let line = t.line();
    let mut out = [0u32; N];
    for (o, &tag) in out.iter_mut().zip(&raw) {
        *o = map.get(tag).ok_or_else(|| {
            t.error_at(
                line,
                format!("{kind} {id} uses node tag {tag}, which is not in $Nodes"),
            )
        })?;
    }
    check::distinct(t, line, raw, kind, id)?;
    Ok(out)
}

/// A readable name for an element type, for `skipped`.
fn type_name(ty: u64) -> String {
    let name = match ty {
        1 => "line",
        2 => "triangle",
        3 => "quadrangle",
        4 => "tetrahedron",
        5 => "hexahedron",
        6 => "prism",
        7 => "pyramid",
        8 => "3-node line",
        9 => "6-node triangle",
        10 => "9-node quadrangle",
        11 => "10-node tetrahedron",
        15 => "point",
        _ => "other",
    };
    format!("gmsh type {ty} ({name})")
}

fn elements_v2(
    t: &mut Tokens,
    map: &NodeMap,
    mesh: &mut TetMeshData,
    skipped: &mut Skipped,
) -> Result<(), IoError> {
    let n = t.usize("the number of elements after \"$Elements\"")?;
    let mut other: HashMap<u64, usize> = HashMap::new();
    for i in 0..n {
        let ctx = || format!("element {} of {n}", i + 1);
        let what = "an element: id, type, number of tags";
        let id = t.u64(what).map_err(|e| e.context(ctx))?;
        let ty = t.u64(what).map_err(|e| e.context(ctx))?;
        let ntags = t.usize(what).map_err(|e| e.context(ctx))?;
        let mut physical = 0;
        for k in 0..ntags {
            let tag = t.i64("an element tag").map_err(|e| e.context(ctx))?;
            if k == 0 {
                physical = i32::try_from(tag).map_err(|_| {
                    t.error(format!("physical tag {tag} does not fit a 32-bit label"))
                })?;
            }
        }
        match ty {
            4 => {
                mesh.tets.push(lookup::<4>(t, map, "tetrahedron", id)?);
                mesh.tet_labels.push(physical);
                mesh.tet_lines.push(t.line());
            }
            2 => mesh
                .boundary_faces
                .push(lookup::<3>(t, map, "triangle", id)?),
            _ => {
                *other.entry(ty).or_default() += 1;
                t.skip_line();
            }
        }
    }
    expect_word(t, "$EndElements")?;
    add_other(skipped, other);
    Ok(())
}

fn elements_v4(
    t: &mut Tokens,
    map: &NodeMap,
    mesh: &mut TetMeshData,
    skipped: &mut Skipped,
) -> Result<(), IoError> {
    let blocks = t.usize("the number of entity blocks after \"$Elements\"")?;
    let n = t.usize("the number of elements")?;
    t.u64("the minimum element tag")?;
    t.u64("the maximum element tag")?;
    let mut other: HashMap<u64, usize> = HashMap::new();
    let mut seen = 0usize;
    for _ in 0..blocks {
        t.usize("an entity dimension (element block header)")?;
        let entity = t.i32("an entity tag")?;
        let ty = t.u64("an element type")?;
        let count = t.usize("the number of elements in the block")?;
        seen = seen.saturating_add(count);
        if seen > n {
            return Err(t.error(format!(
                "element blocks hold more than the {n} elements announced"
            )));
        }
        for _ in 0..count {
            let id = t.u64("an element tag")?;
            match ty {
                4 => {
                    mesh.tets.push(lookup::<4>(t, map, "tetrahedron", id)?);
                    mesh.tet_labels.push(entity);
                    mesh.tet_lines.push(t.line());
                }
                2 => mesh
                    .boundary_faces
                    .push(lookup::<3>(t, map, "triangle", id)?),
                _ => t.skip_line(),
            }
        }
        if ty != 4 && ty != 2 {
            *other.entry(ty).or_default() += count;
        }
    }
    if seen != n {
        return Err(t.error(format!(
            "element blocks hold {seen} elements, the header announced {n}"
        )));
    }
    expect_word(t, "$EndElements")?;
    add_other(skipped, other);
    Ok(())
}

fn add_other(skipped: &mut Skipped, other: HashMap<u64, usize>) {
    let mut other: Vec<_> = other.into_iter().collect();
    other.sort_unstable();
    for (ty, count) in other {
        skipped.add(&type_name(ty), count);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn v41_sparse_tags_entities_and_skipped() {
        let src = b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n5 0 0 0 1 1 1 0 0\n$EndEntities\n\
$Nodes\n2 5 10 900\n0 1 0 1\n900\n1 1 1\n3 5 0 4\n10\n20\n30\n40\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n\
$Elements\n3 4 1 4\n1 2 1 1\n1 10 900\n2 3 2 1\n2 10 20 30\n3 5 4 2\n3 10 20 30 40\n4 40 30 20 900\n$EndElements\n";
        let m = parse(Path::new("a.msh"), src).unwrap();
        assert_eq!(m.vertices.len(), 5);
        assert_eq!(m.tets, vec![[1, 2, 3, 4], [4, 3, 2, 0]]);
        assert_eq!(m.tet_labels, vec![5, 5]);
        assert_eq!(m.boundary_faces, vec![[1, 2, 3]]);
        assert_eq!(m.skipped, vec![("gmsh type 1 (line)".to_string(), 1)]);
    }

    #[test]
    fn v22_physical_tag_and_sparse_nodes() {
        let src = b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 9 \"body\"\n$EndPhysicalNames\n\
$Nodes\n4\n5 0 0 0\n1000000 1 0 0\n7 0 1 0\n8 0 0 1\n$EndNodes\n$Elements\n2\n1 15 2 0 1 5\n2 4 2 9 1 5 1000000 7 8\n$EndElements\n";
        let m = parse(Path::new("b.msh"), src).unwrap();
        assert_eq!(m.tets, vec![[0, 1, 2, 3]]);
        assert_eq!(m.tet_labels, vec![9]);
        assert_eq!(m.skipped, vec![("gmsh type 15 (point)".to_string(), 1)]);
    }
}
