//! The plugin editor (nice-plug-egui on baseview): every parameter grouped the way a player
//! thinks, a live view of the string on its bridge, the nut-force strip and spectrum, a quality
//! indicator and the factory presets. The standalone app opens the same editor.
//!
//! Data flow: the audio thread publishes [`TanpuraSnapshot`](javari_core::snapshot)s through the
//! lock-free [`channel`]; the editor pops the newest at each repaint (50 per second) and does
//! all drawing work (including the FFT) on its own thread.

pub use javari_core::snapshot_channel as channel;
mod controls;
mod spectrum;
mod view;

use crate::params::JavariParams;
use channel::{SnapshotChannel, SnapshotReceiver};
use nice_plug::context::gui::GuiContext;
use nice_plug_egui::{EguiEditor, EguiNiceSettings, Frame, NiceEguiApp, RepaintNotifier};
use std::sync::Arc;
use std::time::Duration;

pub use nice_plug_egui::EguiEditorState;

/// The editor's window size, logical pixels.
pub const EDITOR_SIZE: (u32, u32) = (1180, 780);
/// How often the open editor repaints (the audio thread publishes every 20 ms).
const REPAINT_INTERVAL: Duration = Duration::from_millis(20);

pub type JavariEditor = EguiEditor<EditorApp>;

/// The editor's size and open flag, shared with the wrapper.
pub fn default_state() -> Arc<EguiEditorState> {
    EguiEditorState::from_size(
        nice_plug::editor::dpi::LogicalSize::new(EDITOR_SIZE.0, EDITOR_SIZE.1),
        1.0,
    )
}

/// Builds the editor for the plugin's parameters and its snapshot channel.
pub fn create(
    params: Arc<JavariParams>,
    channel: Arc<SnapshotChannel>,
    state: Arc<EguiEditorState>,
) -> Option<JavariEditor> {
    let app = EditorApp {
        params,
        receiver: SnapshotReceiver::new(channel),
        gui: None,
        analysis: spectrum::ForceAnalysis::default(),
        audition_note: 50,
    };
    nice_plug_egui::create_egui_editor(
        state,
        RepaintNotifier::new(),
        EguiNiceSettings::new().with_tile("Javari"),
        app,
    )
}

/// The editor's state on the GUI thread.
pub struct EditorApp {
    params: Arc<JavariParams>,
    receiver: SnapshotReceiver,
    gui: Option<GuiContext>,
    analysis: spectrum::ForceAnalysis,
    /// MIDI note the audition button plucks.
    audition_note: u8,
}

impl NiceEguiApp for EditorApp {
    fn build(
        &mut self,
        egui_ctx: egui::Context,
        nice_gui_ctx: GuiContext,
        _frame: &mut Frame,
    ) -> Result<(), nice_plug_egui::baseview::HandlerError> {
        egui_ctx.set_visuals(egui::Visuals::dark());
        self.gui = Some(nice_gui_ctx);
        self.receiver.channel().set_consumer_open(true);
        Ok(())
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut Frame) {
        // Every frame that arrived goes into the spectrogram, so its time axis stays 20 ms per
        // column even when the window repaints less often.
        let analysis = &mut self.analysis;
        self.receiver.poll_each(|frame| analysis.update(frame));
        ui.ctx().request_repaint_after(REPAINT_INTERVAL);
        let Some(gui) = self.gui.clone() else {
            return;
        };
        let setter = gui.param_setter();
        let snapshot = self.receiver.latest();

        egui::Panel::top("javari-top").show(ui, |ui| {
            controls::top_bar(
                ui,
                &self.params,
                &setter,
                snapshot,
                self.receiver.channel(),
                &mut self.audition_note,
            );
        });
        egui::Panel::left("javari-parameters")
            .resizable(false)
            .exact_size(372.0)
            .show(ui, |ui| {
                controls::parameter_groups(ui, &self.params, &setter);
            });
        egui::CentralPanel::default_margins().show(ui, |ui| {
            view::live_view(ui, snapshot, &mut self.analysis, &self.params);
        });
    }

    fn editor_closed(&mut self) {
        self.receiver.channel().set_consumer_open(false);
        self.gui = None;
    }
}
