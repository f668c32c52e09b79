//! Colliders (parry3d) against particles (issue 5; not built yet).
