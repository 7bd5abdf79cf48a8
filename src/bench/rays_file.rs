//! The plain ray and hit files other tracers read and write (`bench lbvh --rays-file
//! --dump-rays --dump-hits`), little-endian, no header:
//!
//! - a ray is 32 bytes: `f32 ox, oy, oz, dx, dy, dz, tmin, tmax`;
//! - a hit is 8 bytes: `f32 t, u32 triangle`, a miss `(+inf, 0xFFFFFFFF)`; triangles
//!   are numbered in file order after fan triangulation (the order the loaders keep).

use crate::error::{Error, Result};
use crate::gpu_types::{Hit, Ray};
use crate::shader_defines::BVH_INVALID;

pub const RAY_BYTES: usize = 32;
pub const HIT_BYTES: usize = 8;

fn f32_at(b: &[u8], k: usize) -> f32 {
    f32::from_le_bytes(b[4 * k..4 * k + 4].try_into().expect("4 bytes"))
}

/// Rays from a file's bytes; `what` names the file in errors. Every value must be
/// finite (`tmax` may be +inf), the direction non-zero and `tmin <= tmax`.
pub fn read_rays(bytes: &[u8], what: &str) -> Result<Vec<Ray>> {
    let bad = |why: String| Error::Input(format!("rays file {what}: {why}"));
    if bytes.is_empty() || !bytes.len().is_multiple_of(RAY_BYTES) {
        return Err(bad(format!(
            "{} bytes: not a whole number of 32-byte rays (f32 ox,oy,oz,dx,dy,dz,tmin,tmax), or empty",
            bytes.len()
        )));
    }
    bytes
        .chunks_exact(RAY_BYTES)
        .enumerate()
        .map(|(n, c)| {
            let f: Vec<f32> = (0..8).map(|k| f32_at(c, k)).collect();
            let ray = Ray {
                origin: [f[0], f[1], f[2]],
                dir: [f[3], f[4], f[5]],
                tmin: f[6],
                tmax: f[7],
            };
            let why = if !f[..7].iter().all(|x| x.is_finite()) || f[7].is_nan() {
                Some("a NaN or infinite origin, direction or tmin")
            } else if f[3..6].iter().all(|x| *x == 0.0) {
                Some("a zero direction")
            } else if f[6] > f[7] {
                Some("tmin > tmax")
            } else {
                None
            };
            if let Some(why) = why {
                return Err(bad(format!("ray {n} is not a ray ({why}): {f:?}")));
            }
            Ok(ray)
        })
        .collect()
}

/// Rays as a file's bytes.
pub fn write_rays(rays: &[Ray]) -> Vec<u8> {
    rays.iter()
        .flat_map(|r| {
            [
                r.origin[0],
                r.origin[1],
                r.origin[2],
                r.dir[0],
                r.dir[1],
                r.dir[2],
                r.tmin,
                r.tmax,
            ]
            .into_iter()
            .flat_map(f32::to_le_bytes)
        })
        .collect()
}

/// Hits as a file's bytes: closest `t` and triangle, a miss as `(+inf, 0xFFFFFFFF)`.
pub fn write_hits(hits: &[Hit]) -> Vec<u8> {
    hits.iter()
        .flat_map(|h| {
            let (t, prim) = if h.prim == BVH_INVALID {
                (f32::INFINITY, u32::MAX)
            } else {
                (h.t, h.prim)
            };
            t.to_le_bytes().into_iter().chain(prim.to_le_bytes())
        })
        .collect()
}

/// Hits from a file's bytes (for tests and comparisons): `(t, triangle)` pairs.
pub fn read_hits(bytes: &[u8], what: &str) -> Result<Vec<(f32, u32)>> {
    if !bytes.len().is_multiple_of(HIT_BYTES) {
        return Err(Error::Input(format!(
            "hits file {what}: {} bytes, not a whole number of 8-byte hits",
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(HIT_BYTES)
        .map(|c| (f32_at(c, 0), u32::from_le_bytes(c[4..8].try_into().expect("4 bytes"))))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_and_hits_round_trip_in_the_plain_layout() {
        let rays = vec![
            Ray {
                origin: [1.0, 2.0, 3.0],
                dir: [0.0, 0.0, -1.0],
                tmin: 0.0,
                tmax: f32::INFINITY,
            },
            Ray {
                origin: [-1.5, 0.25, 8.0],
                dir: [0.5, -0.5, 0.0],
                tmin: 1e-3,
                tmax: 100.0,
            },
        ];
        let bytes = write_rays(&rays);
        assert_eq!(bytes.len(), 64);
        assert_eq!(f32_at(&bytes, 3), 0.0, "dx is the 4th float");
        assert_eq!(f32_at(&bytes, 6), 0.0, "tmin the 7th");
        assert_eq!(read_rays(&bytes, "r").unwrap(), rays);
        let hits = [
            Hit {
                t: 2.5,
                prim: 7,
                u: 0.1,
                v: 0.2,
            },
            Hit {
                t: 100.0,
                prim: BVH_INVALID,
                u: 0.0,
                v: 0.0,
            },
        ];
        let h = read_hits(&write_hits(&hits), "h").unwrap();
        assert_eq!(h, vec![(2.5, 7), (f32::INFINITY, u32::MAX)]);
    }

    #[test]
    fn bad_ray_files_are_named() {
        assert!(read_rays(&[0; 31], "r.bin").unwrap_err().to_string().contains("r.bin"));
        assert!(read_rays(&[], "r.bin").is_err());
        let mut nan = write_rays(&[Ray {
            origin: [0.0; 3],
            dir: [1.0, 0.0, 0.0],
            tmin: 0.0,
            tmax: 1.0,
        }]);
        nan[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(read_rays(&nan, "r").unwrap_err().to_string().contains("ray 0"));
        let zero = write_rays(&[Ray::default()]);
        assert!(read_rays(&zero, "r").is_err(), "a zero direction");
    }
}
