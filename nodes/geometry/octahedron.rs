//! The regular octahedron as a table: its six vertex directions and eight faces. The
//! rasterizer splats points as octahedra and the curvature tests check Gauss-Bonnet on one,
//! so both read this one table.

/// Unit vertex directions: +x, -x, +y, -y, +z, -z.
pub const DIRS: [[f64; 3]; 6] = [
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
];

/// Faces as indices into [`DIRS`], counter-clockwise seen from outside: (+x, +y, +z) and
/// its mirror images.
pub const FACES: [[u32; 3]; 8] = [
    [0, 2, 4],
    [2, 1, 4],
    [1, 3, 4],
    [3, 0, 4],
    [2, 0, 5],
    [1, 2, 5],
    [3, 1, 5],
    [0, 3, 5],
];

/// The octahedron's vertex positions at half-diagonal `r` around `centre`.
pub fn positions(centre: [f64; 3], r: f64) -> [[f64; 3]; 6] {
    DIRS.map(|d| {
        [
            centre[0] + r * d[0],
            centre[1] + r * d[1],
            centre[2] + r * d[2],
        ]
    })
}
