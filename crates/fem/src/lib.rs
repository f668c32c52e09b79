//! Reference finite elements for the accuracy benchmark (issue 6; not built yet).
