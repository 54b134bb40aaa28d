use javari_core::tanpura::*;
fn main() {
    for (thread, f0) in [
        (true, 189.0),
        (false, 189.0),
        (true, 100.0),
        (true, 400.0),
        (true, 800.0),
    ] {
        let mut s = VoiceSettings::default();
        s.fundamental_hz = f0;
        s.thread_enabled = thread;
        let cfg = s.string_config(44100.0);
        let mut st = javari_core::tanpura_string::TanpuraString::new(cfg);
        let f = st.linearised_fundamental_hz();
        println!(
            "thread {thread} f0 {f0}: nominal-T linearised {f:.3} ({:+.1} c) contact end {:?}",
            javari_core::analysis::cents(f, f0),
            st.rest_contact_end_m()
        );
    }
}
