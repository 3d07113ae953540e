//! What every target shares.

/// libfuzzer-sys installs a panic hook that aborts on *any* panic, even one the code under test
/// catches. The loaders catch a parser's panic on purpose (tobj's index overflow becomes a
/// diagnosed error, see scenes/src/load/obj.rs), so the targets restore the default hook: a caught
/// panic is handled as in the harness, and an uncaught one still ends the input as a crash
/// (libfuzzer-sys aborts when the target itself panics).
pub fn unwind_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| drop(std::panic::take_hook()));
}
