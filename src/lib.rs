//! placeholder
pub use myriad_cluster_math as cluster_math;
