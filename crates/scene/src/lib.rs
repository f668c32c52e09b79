//! Scene files and the simulation driver (issue 5; not built yet).
