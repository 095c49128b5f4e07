//! Learning-curve statistics and plots (being written).
