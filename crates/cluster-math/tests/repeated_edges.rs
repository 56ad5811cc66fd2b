//! Grids thinner than the f32 depths they span: several slice edges round to one f32 value,
//! the near plane's among them (`slice_start_depth(1) == near`). `slice_of_depth` must still
//! give the last slice whose edge is `<= d` (the edge table's partition point) for every f32
//! depth, without underflowing below slice 0 (mutation audit: the downward correction loop of
//! `slice_of_depth` was never run with a depth on a repeated edge).

use glam::UVec3;
use myriad_cluster_math::{ClusterGrid, DepthSlicing};

#[test]
fn slice_of_depth_is_the_partition_point_on_grids_with_repeated_f32_edges() {
    let mut repeated_near_edges = 0;
    for near in [1.0f32, 5.0, 0.1, 1000.0] {
        for ulps in 1u32..=6 {
            let far = f32::from_bits(near.to_bits() + ulps);
            let first_slice_depth = f32::from_bits(near.to_bits() + 1);
            for z in [2u32, 3, 4, 5, 8, 13, 64] {
                for slicing in [
                    DepthSlicing::Linear,
                    DepthSlicing::Log,
                    DepthSlicing::LogWithNearSlice { first_slice_depth },
                ] {
                    let Ok(grid) = ClusterGrid::try_new(UVec3::new(1, 1, z), slicing, near, far)
                    else {
                        continue;
                    };
                    let mut edges = Vec::new();
                    grid.fill_slice_edges(&mut edges);
                    if z > 2 && edges[1] == near {
                        repeated_near_edges += 1;
                    }
                    for bits in near.to_bits() - 2..=far.to_bits() + 2 {
                        let d = f32::from_bits(bits);
                        let want = (edges.partition_point(|&e| e <= d) as u32).clamp(1, z) - 1;
                        assert_eq!(
                            grid.slice_of_depth(d),
                            want,
                            "{grid:?} depth {d} (edges {edges:?})"
                        );
                    }
                }
            }
        }
    }
    assert!(repeated_near_edges > 0, "no grid repeated the near edge");
}
