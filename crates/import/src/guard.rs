//! Containing panics of dependencies: a closure is run so that a panic inside it becomes an error
//! message instead of ending the process or a batch, and prints nothing (the error is reported once,
//! as a one-line error naming the file). Panics outside a guarded call print as usual.

// Fuzz builds use only the pass-through `contain`.
#![cfg_attr(fuzzing, allow(dead_code, unused_imports))]

use std::cell::{Cell, RefCell};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    static QUIET: Cell<bool> = const { Cell::new(false) };
    static MESSAGE: RefCell<Option<String>> = const { RefCell::new(None) };
}

static HOOK: Once = Once::new();

/// Runs `f`; a panic inside it is caught and returned as its message.
///
/// Fuzz builds (`--cfg fuzzing`, fuzz/run) let the panic through, so that the fuzzer reports every
/// input that reaches a dependency's panic, contained or not.
#[cfg(fuzzing)]
pub(crate) fn contain<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    Ok(f())
}

/// Runs `f`; a panic inside it is caught and returned as its message.
#[cfg(not(fuzzing))]
pub(crate) fn contain<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if QUIET.with(Cell::get) {
                let payload = info.payload();
                let text = payload
                    .downcast_ref::<&str>()
                    .map(|s| (*s).to_string())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "a panic".to_string());
                MESSAGE.with(|m| *m.borrow_mut() = Some(text));
            } else {
                previous(info);
            }
        }));
    });
    let was = QUIET.with(|q| q.replace(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(was));
    result.map_err(|_| {
        MESSAGE
            .with(|m| m.borrow_mut().take())
            .unwrap_or_else(|| "a panic".to_string())
    })
}

#[cfg(all(test, not(fuzzing)))]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_its_message_and_values_pass_through() {
        assert_eq!(contain(|| 7), Ok(7));
        let v: Vec<u8> = Vec::new();
        let e = contain(|| v[3]).unwrap_err();
        assert!(e.contains("index out of bounds"), "{e}");
        // Nested guards each get their own panic.
        let outer = contain(|| contain(|| panic!("inner")).unwrap_err());
        assert_eq!(outer, Ok("inner".to_string()));
    }
}
