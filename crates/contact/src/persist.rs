//! The colliders' part of a checkpoint: what steps change (each ball's centre, velocity and
//! carried forces, the reference mass fixed at the first implicit step); shapes and
//! coefficients come from the setup.

use perifrac_checkpoint::{expect_count, CheckpointError, Reader, Writer};

use crate::colliders::Colliders;
use crate::math::{from_parry, to_parry};

impl Colliders {
    /// Writes the balls' motion and the reference mass.
    pub fn save(&self, w: &mut Writer) {
        w.tag("colliders");
        w.usize(self.grounds.len());
        w.usize(self.balls.len());
        for b in &self.balls {
            w.array(&[
                from_parry(b.pose.translation),
                b.velocity,
                b.force,
                b.reaction,
                b.ground_force,
            ]);
        }
        w.bool(self.reference_mass.is_some());
        w.f64(self.reference_mass.unwrap_or(0.0));
    }

    /// Reads what [`Colliders::save`] wrote into colliders built from the same scene.
    pub fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("colliders")?;
        expect_count(
            "ground planes",
            self.grounds.len(),
            r.usize("ground planes")?,
        )?;
        expect_count("balls", self.balls.len(), r.usize("balls")?)?;
        for b in &mut self.balls {
            let mut v = [[0.0; 3]; 5];
            r.array_into("ball motion", &mut v)?;
            b.pose.translation = to_parry(v[0]);
            b.velocity = v[1];
            b.force = v[2];
            b.reaction = v[3];
            b.ground_force = v[4];
        }
        let has = r.bool("reference mass")?;
        let m = r.f64("reference mass")?;
        self.reference_mass = has.then_some(m);
        Ok(())
    }
}
