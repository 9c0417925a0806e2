//! Connected components of a mesh (faces sharing a vertex, `rfta_mesh::face_components`) removed
//! by the caller's verdict.

use rfta_geom::{Aabb, TriMesh};
use rfta_mesh::face_components;

/// Why a component of the mesh goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Island {
    /// A component other than the largest that the caller's verdict finds small and unwitnessed
    /// (the pipeline: below `Params::min_island` spacings, enclosing no sample of its inside's
    /// sign, closing no sample's gap).
    Small,
    /// A component the caller finds contradicted, whatever its size (the pipeline: every vertex
    /// inside a sample sphere and no sample of its inside's sign enclosed, or an inward shell with
    /// no other component around it).
    Unsupported,
}

/// Removes the connected components (by shared vertices) that `unsupported` condemns (given their
/// faces; unless it condemns all), then those other than the largest remaining (by faces) that
/// `verdict` condemns, given their faces, bounding box and the largest's faces; unused vertices
/// are dropped. Returns
/// the mesh and the number removed for each [`Island`] reason (`unsupported`: unsupported).
pub fn remove_islands(
    mesh: &TriMesh,
    unsupported: impl Fn(&[usize]) -> bool,
    verdict: impl Fn(&[usize], Aabb, &[usize]) -> Option<Island>,
) -> (TriMesh, [usize; 2]) {
    let n = mesh.vertices.len();
    let faces_of = face_components(mesh);
    let bounds: Vec<Aabb> = faces_of
        .iter()
        .map(|faces| {
            faces
                .iter()
                .flat_map(|&f| mesh.faces[f])
                .fold(Aabb::EMPTY, |b, v| b.grow(mesh.vertices[v as usize]))
        })
        .collect();
    let mut removed = [0usize; 2];
    if faces_of.len() < 2 {
        return (mesh.clone(), removed);
    }
    let mut out: Vec<bool> = faces_of.iter().map(|f| unsupported(f)).collect();
    if out.iter().all(|&o| o) {
        out.fill(false);
    }
    let largest = (0..faces_of.len())
        .filter(|&c| !out[c])
        .max_by_key(|&c| (faces_of[c].len(), std::cmp::Reverse(c)))
        .unwrap_or(0);
    let keep: Vec<bool> = (0..faces_of.len())
        .map(|c| {
            if out[c] {
                removed[Island::Unsupported as usize] += 1;
                return false;
            }
            if c == largest {
                return true;
            }
            match verdict(&faces_of[c], bounds[c], &faces_of[largest]) {
                Some(why) => {
                    removed[why as usize] += 1;
                    false
                }
                None => true,
            }
        })
        .collect();
    if keep.iter().all(|&k| k) {
        return (mesh.clone(), removed);
    }
    let mut remap = vec![u32::MAX; n];
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut kept = vec![false; mesh.faces.len()];
    for (c, faces) in faces_of.iter().enumerate() {
        for &f in faces {
            kept[f] = keep[c];
        }
    }
    for (f, &k) in mesh.faces.iter().zip(&kept) {
        if !k {
            continue;
        }
        let g = f.map(|v| {
            if remap[v as usize] == u32::MAX {
                remap[v as usize] = vertices.len() as u32;
                vertices.push(mesh.vertices[v as usize]);
            }
            remap[v as usize]
        });
        faces.push(g);
    }
    (TriMesh { vertices, faces }, removed)
}
