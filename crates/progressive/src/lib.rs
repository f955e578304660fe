//! radlab-progressive (to be written).
