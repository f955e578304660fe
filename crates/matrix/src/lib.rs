//! radlab-matrix (to be written).
