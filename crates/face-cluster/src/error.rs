//! Errors of the face-cluster crate, each saying how to fix its cause.

/// What can go wrong building, saving or loading a face-cluster hierarchy.
#[derive(Debug, thiserror::Error)]
pub enum FaceClusterError {
    /// A build parameter is out of range.
    #[error("face-cluster parameter '{field}': {message}")]
    InvalidParams {
        /// The parameter (kebab-case, as in experiment files).
        field: &'static str,
        /// What is wrong and the accepted range.
        message: String,
    },
    /// The bytes are not a face-cluster hierarchy this version of radlab wrote.
    #[error(
        "not a readable face-cluster hierarchy cache ({message}); delete the cache file and it is rebuilt"
    )]
    CacheFormat {
        /// What did not match.
        message: String,
    },
    /// The cache holds a hierarchy of another mesh or other build parameters.
    #[error(
        "the face-cluster cache was built for another mesh or other parameters (digest {found}, expected \
         {expected}); rebuild it, or look it up under the digest of this scene"
    )]
    CacheStale {
        /// Digest in the cache, hex.
        found: String,
        /// Digest of this scene and parameters, hex.
        expected: String,
    },
    /// Reading or writing the cache failed.
    #[error("reading or writing the face-cluster cache failed: {0}")]
    CacheIo(#[from] std::io::Error),
}
