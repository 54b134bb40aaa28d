//! The standalone Javari app (feature `standalone`): cpal or JACK audio, MIDI input from the
//! command line options nice-plug offers (`--help`).

use javari::Javari;
use nice_plug::prelude::*;

fn main() {
    nice_export_standalone::<Javari>();
}
