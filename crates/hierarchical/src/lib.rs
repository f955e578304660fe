//! radlab-hierarchical (to be written).
