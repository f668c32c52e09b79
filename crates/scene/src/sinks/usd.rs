//! `NAME.usda`: the run's frames as one USD cache, made once the last frame is written (as
//! `perifrac export` makes it from any run directory).

use std::path::Path;

use super::{Finished, FrameFiles, FrameSink, FrameView, Written};
use crate::error::SceneError;
use crate::usd::UsdLayout;

/// Writes the USD cache at the end of the run.
pub struct UsdSink {
    /// One mesh, or one prim per fragment.
    pub layout: UsdLayout,
}

impl FrameSink for UsdSink {
    fn write(&self, _: &Path, _: &FrameView, _: &mut FrameFiles) -> Written {
        Ok(())
    }

    fn finish(&self, dir: &Path) -> Result<Option<Finished>, SceneError> {
        crate::usd::export_usd(dir, None, self.layout, None).map(|r| Some(Finished::Usd(r)))
    }
}
