//! The `--grid` and `--depth` options, shared by every command that builds a cluster grid.

use anyhow::{Result, bail, ensure};
use myriad::cluster_math::glam::UVec3;
use myriad::scene::{ClusterGrid, DepthSlicing};

/// What `--depth` accepts, for its errors.
const DEPTH_CHOICES: &str = "log, linear or log_near:D (a first slice to D metres, \
     then log slices to the far plane)";

/// `"24x12x16"` as grid dimensions.
pub(super) fn parse_grid(flag: &str, text: &str) -> Result<UVec3> {
    let parts: Vec<&str> = text.split('x').collect();
    let dims: Option<Vec<u32>> = parts.iter().map(|p| p.parse().ok()).collect();
    match dims.as_deref() {
        Some(&[x, y, z]) if x >= 1 && y >= 1 && z >= 1 => {
            let clusters = ClusterGrid::clusters_in(UVec3::new(x, y, z));
            ensure!(
                clusters <= u32::MAX as u128,
                "{flag} {text:?}: {clusters} clusters; cluster ids are u32, so at most {}",
                u32::MAX
            );
            Ok(UVec3::new(x, y, z))
        }
        _ => bail!("{flag} {text:?}: expected XxYxZ with each dimension >= 1, e.g. 24x12x16"),
    }
}

/// `"log"`, `"linear"` or `"log_near:D"` as a depth slicing. A near slice's depth is checked
/// against the camera by [`check_slicing`], once the camera is known.
pub(super) fn parse_slicing(text: &str) -> Result<DepthSlicing> {
    match text.split_once(':') {
        None if text == "log" => Ok(DepthSlicing::Log),
        None if text == "linear" => Ok(DepthSlicing::Linear),
        Some(("log_near", depth)) => match depth.parse::<f32>() {
            Ok(d) if d.is_finite() && d > 0.0 => Ok(DepthSlicing::LogWithNearSlice {
                first_slice_depth: d,
            }),
            _ => bail!("--depth {text:?}: the near slice's depth must be a finite number > 0"),
        },
        _ => bail!("--depth {text:?}: expected {DEPTH_CHOICES}"),
    }
}

/// Checks that `slicing` fits a grid of `slices` depth slices over `[near, far]`: a near slice
/// must end strictly inside the range (what [`myriad::scene::ClusterGrid::new`] asserts).
pub(super) fn check_slicing(slicing: DepthSlicing, slices: u32, near: f32, far: f32) -> Result<()> {
    if let DepthSlicing::LogWithNearSlice { first_slice_depth } = slicing {
        ensure!(
            slices == 1 || (first_slice_depth > near && first_slice_depth < far),
            "--depth log_near:{first_slice_depth}: the near slice must end strictly between the \
             camera's near ({near}) and far ({far}) planes"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_slicings_parse_and_are_checked_against_the_camera() {
        assert_eq!(parse_slicing("log").unwrap(), DepthSlicing::Log);
        assert_eq!(parse_slicing("linear").unwrap(), DepthSlicing::Linear);
        let near = parse_slicing("log_near:5").unwrap();
        assert_eq!(
            near,
            DepthSlicing::LogWithNearSlice {
                first_slice_depth: 5.0
            }
        );
        for bad in [
            "cubic",
            "log:5",
            "log_near",
            "log_near:",
            "log_near:-1",
            "log_near:inf",
        ] {
            let e = parse_slicing(bad).unwrap_err().to_string();
            assert!(e.contains(bad), "{e}");
        }
        assert!(check_slicing(near, 16, 0.1, 100.0).is_ok());
        assert!(check_slicing(near, 1, 0.1, 4.0).is_ok());
        let e = check_slicing(near, 16, 0.1, 4.0).unwrap_err().to_string();
        assert!(e.contains("near (0.1) and far (4)"), "{e}");
        assert!(check_slicing(DepthSlicing::Log, 16, 0.1, 4.0).is_ok());
    }

    #[test]
    fn grids_name_the_flag_and_the_cluster_limit() {
        assert_eq!(
            parse_grid("--grid", "24x12x16").unwrap(),
            UVec3::new(24, 12, 16)
        );
        let e = parse_grid("--grid", "24x0x16").unwrap_err().to_string();
        assert!(e.contains("--grid \"24x0x16\""), "{e}");
        for bad in ["24x12", "0x1x1", "axbxc", "24x12x16x2"] {
            assert!(parse_grid("--grid", bad).is_err(), "{bad}");
        }
        let e = parse_grid("--grid", "4096x4096x4096")
            .unwrap_err()
            .to_string();
        assert!(e.contains("68719476736 clusters"), "{e}");
        // 2^64 clusters wrapped to 0 in u64 and passed (audit).
        let e = parse_grid("--grid", "4194304x2097152x2097152")
            .unwrap_err()
            .to_string();
        assert!(e.contains("18446744073709551616 clusters"), "{e}");
    }

    #[test]
    fn a_near_slice_must_be_deeper_than_zero() {
        let e = parse_slicing("log_near:0").unwrap_err().to_string();
        assert!(e.contains("log_near:0") && e.contains("> 0"), "{e}");
        assert_eq!(
            parse_slicing("log_near:1e-30").unwrap(),
            DepthSlicing::LogWithNearSlice {
                first_slice_depth: 1e-30
            }
        );
    }
}
