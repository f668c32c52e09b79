//! Tet mesh topology (being written).
