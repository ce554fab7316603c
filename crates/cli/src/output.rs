//! Printing to stdout without panicking when the reader went away
//! (`drivebus dump | head`): a closed pipe ends the program quietly.

use std::io::Write;

/// Writes `args` and a newline to stdout; exits 0 if stdout is closed.
pub fn line(args: std::fmt::Arguments<'_>) {
    let mut o = std::io::stdout().lock();
    if writeln!(o, "{args}").and_then(|()| o.flush()).is_err() {
        std::process::exit(0);
    }
}

/// Writes `args` to stdout; exits 0 if stdout is closed.
pub fn text(args: std::fmt::Arguments<'_>) {
    let mut o = std::io::stdout().lock();
    if write!(o, "{args}").and_then(|()| o.flush()).is_err() {
        std::process::exit(0);
    }
}

/// `println!` that survives a closed stdout.
macro_rules! outln {
    () => { $crate::output::line(format_args!("")) };
    ($($t:tt)*) => { $crate::output::line(format_args!($($t)*)) };
}

/// `print!` that survives a closed stdout.
macro_rules! out {
    ($($t:tt)*) => { $crate::output::text(format_args!($($t)*)) };
}

pub(crate) use {out, outln};

/// Prints the `--json` form of an error on stdout: one object.
pub fn json_error(code: &str, message: &str, extra: serde_json::Value) {
    let mut e = serde_json::json!({"code": code, "message": message});
    if let (Some(obj), serde_json::Value::Object(x)) = (e.as_object_mut(), extra) {
        obj.extend(x);
    }
    line(format_args!("{}", serde_json::json!({ "error": e })));
}

/// `--json` or a line of text.
pub fn emit(json: bool, value: serde_json::Value, text: impl FnOnce() -> String) {
    if json {
        line(format_args!("{value}"));
    } else {
        line(format_args!("{}", text()));
    }
}
