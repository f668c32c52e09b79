//! Peridynamic particles, families, materials, fracture and integrators (issue 3; not built yet).
