//! Validation and bookkeeping shared by the tet-mesh readers.

use crate::tokens::Tokens;
use crate::IoError;

/// Converts file indices of one element to 0-based `u32`, checking range and repetition.
///
/// `raw` are the indices as written; `base` is the file's first index (0 or 1); `kind` and `id`
/// name the element ("tet", 17) and `source` the vertex list ("the .node file", "the file").
#[allow(clippy::too_many_arguments)]
pub(crate) fn element<const N: usize>(
    tokens: &Tokens,
    line: usize,
    raw: [u64; N],
    base: u64,
    num_vertices: usize,
    kind: &str,
    id: u64,
    source: &str,
) -> Result<[u32; N], IoError> {
    let mut out = [0u32; N];
    for (slot, &r) in out.iter_mut().zip(raw.iter()) {
        let index = r
            .checked_sub(base)
            .filter(|&i| i < num_vertices as u64)
            .and_then(|i| u32::try_from(i).ok());
        match index {
            Some(i) => *slot = i,
            None => {
                let note = if r < base {
                    format!("; indices start at {base}")
                } else {
                    String::new()
                };
                return Err(tokens.error_at(
                    line,
                    format!(
                        "vertex index {r} out of range ({source} has {num_vertices} vertices{note})"
                    ),
                ));
            }
        }
    }
    distinct(tokens, line, raw, kind, id)?;
    Ok(out)
}

/// Errors when an element lists the same vertex (as written in the file) twice.
pub(crate) fn distinct<const N: usize>(
    tokens: &Tokens,
    line: usize,
    raw: [u64; N],
    kind: &str,
    id: u64,
) -> Result<(), IoError> {
    for a in 0..N {
        for b in a + 1..N {
            if raw.get(a) == raw.get(b) {
                let list: Vec<String> = raw.iter().map(u64::to_string).collect();
                return Err(tokens.error_at(
                    line,
                    format!(
                        "{kind} {id} repeats vertex index {}: {}",
                        raw.get(a).copied().unwrap_or(0),
                        list.join(" ")
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Counts of element kinds a reader skipped, in first-seen order.
#[derive(Default)]
pub(crate) struct Skipped(Vec<(String, usize)>);

impl Skipped {
    /// Adds `n` elements of kind `name`.
    pub fn add(&mut self, name: &str, n: usize) {
        if n == 0 {
            return;
        }
        match self.0.iter_mut().find(|(k, _)| k == name) {
            Some((_, count)) => *count += n,
            None => self.0.push((name.to_string(), n)),
        }
    }

    /// The list for [`crate::TetMeshData::skipped`].
    pub fn into_vec(self) -> Vec<(String, usize)> {
        self.0
    }
}

/// Checks that a writer's tets and faces index existing vertices and labels match tets.
pub(crate) fn mesh_for_writing(
    file: &std::path::Path,
    mesh: &crate::TetMeshData,
) -> Result<(), IoError> {
    let n = mesh.vertices.len();
    if mesh.tet_labels.len() != mesh.tets.len() {
        return Err(IoError::invalid(
            file,
            format!(
                "{} tet labels for {} tets",
                mesh.tet_labels.len(),
                mesh.tets.len()
            ),
        ));
    }
    let tet_bad = mesh
        .tets
        .iter()
        .position(|t| t.iter().any(|&i| i as usize >= n));
    if let Some(t) = tet_bad {
        return Err(IoError::invalid(
            file,
            format!("tet {t} has a vertex index out of range ({n} vertices)"),
        ));
    }
    let face_bad = mesh
        .boundary_faces
        .iter()
        .position(|f| f.iter().any(|&i| i as usize >= n));
    if let Some(f) = face_bad {
        return Err(IoError::invalid(
            file,
            format!("boundary face {f} has a vertex index out of range ({n} vertices)"),
        ));
    }
    Ok(())
}
