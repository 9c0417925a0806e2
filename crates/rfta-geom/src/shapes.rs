//! Closed, outward-oriented triangle meshes of analytic shapes, for examples and tests.
//!
//! Each mesh approximates a shape whose exact signed distance is known, so tests can compare
//! against the shape rather than against rfta's own output.

use std::collections::HashMap;
use std::f64::consts::TAU;

use glam::DVec3;

use crate::TriMesh;

/// The regular octahedron with vertices at `+-radius` on each axis (6 vertices, 8 faces).
pub fn octahedron(radius: f64) -> TriMesh {
    let vertices = vec![
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Y,
        DVec3::Z,
        -DVec3::Z,
    ]
    .into_iter()
    .map(|v| v * radius)
    .collect();
    let faces = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    TriMesh { vertices, faces }
}

/// An icosphere: the icosahedron subdivided `subdivisions` times, vertices pushed onto the sphere
/// of `radius` about the origin (`10 * 4^s + 2` vertices, `20 * 4^s` faces).
pub fn icosphere(radius: f64, subdivisions: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|v| DVec3::from_array(*v).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<DVec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *midpoints.entry(key).or_insert_with(|| {
                vertices.push((vertices[a as usize] + vertices[b as usize]).normalize());
                (vertices.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut vertices);
            let bc = midpoint(b, c, &mut vertices);
            let ca = midpoint(c, a, &mut vertices);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    let mut mesh = TriMesh { vertices, faces };
    mesh.map_vertices(|v| v * radius);
    orient_convex_outward(&mut mesh);
    mesh
}

/// The torus about the z axis with tube centre radius `major` and tube radius `minor`,
/// `n_major` segments around the axis and `n_minor` around the tube (genus 1).
pub fn torus(major: f64, minor: f64, n_major: u32, n_minor: u32) -> TriMesh {
    let (nu, nv) = (n_major.max(3), n_minor.max(3));
    let mut vertices = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        let theta = TAU * i as f64 / nu as f64;
        for j in 0..nv {
            let phi = TAU * j as f64 / nv as f64;
            let ring = major + minor * phi.cos();
            vertices.push(DVec3::new(
                ring * theta.cos(),
                ring * theta.sin(),
                minor * phi.sin(),
            ));
        }
    }
    let id = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut faces = Vec::with_capacity((2 * nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            // Edges along theta then phi: (d theta) x (d phi) points out of the tube.
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh { vertices, faces }
}

/// The axis-aligned box `[-half, half]` (8 vertices, 12 faces).
pub fn cuboid(half: DVec3) -> TriMesh {
    let vertices = (0..8)
        .map(|i| DVec3::new(bit(i, 0), bit(i, 1), bit(i, 2)) * half)
        .collect();
    // Quads per face (corner index bits: x = 1, y = 2, z = 4), split into two triangles.
    let quads: [[u32; 4]; 6] = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    let faces = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let mut mesh = TriMesh { vertices, faces };
    orient_convex_outward(&mut mesh);
    mesh
}

fn bit(i: u32, b: u32) -> f64 {
    if i >> b & 1 == 1 { 1.0 } else { -1.0 }
}

/// Orients each face of a convex mesh around the origin so that its normal points away from it.
fn orient_convex_outward(mesh: &mut TriMesh) {
    for f in 0..mesh.faces.len() {
        let [a, b, c] = mesh.triangle(f);
        if (b - a).cross(c - a).dot(a + b + c) < 0.0 {
            mesh.faces[f].swap(1, 2);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    #[test]
    fn shapes_enclose_their_analytic_volumes() {
        // Volumes of inscribed polyhedra approach the analytic ones from below.
        let ico = icosphere(1.0, 4);
        let v = ico.signed_volume();
        assert!(
            v > 0.99 * 4.0 / 3.0 * PI && v < 4.0 / 3.0 * PI,
            "sphere volume {v}"
        );
        assert_eq!((ico.n_vertices(), ico.n_faces()), (2562, 5120));
        let t = torus(0.6, 0.25, 96, 48);
        let vt = t.signed_volume();
        let exact = 2.0 * PI * PI * 0.6 * 0.25 * 0.25;
        assert!(
            vt > 0.99 * exact && vt < exact,
            "torus volume {vt} vs {exact}"
        );
        let c = cuboid(DVec3::new(0.5, 1.0, 1.5));
        assert!((c.signed_volume() - 6.0).abs() < 1e-12);
        assert!((c.area() - 2.0 * (2.0 + 3.0 + 6.0)).abs() < 1e-12);
        assert!((octahedron(1.0).signed_volume() - 4.0 / 3.0).abs() < 1e-12);
    }
}
