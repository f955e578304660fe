//! radlab-pathtrace (to be written).
