//! Mesh readers and writers (being written).
