//! CSV lines (RFC 4180) for `monitor --csv` and `dump --pdo --csv`.

/// One CSV line: fields quoted where they hold a comma, a quote or a line break.
pub fn line<S: AsRef<str>>(fields: impl IntoIterator<Item = S>) -> String {
    let mut out = String::new();
    for (k, f) in fields.into_iter().enumerate() {
        if k > 0 {
            out.push(',');
        }
        let f = f.as_ref();
        if f.contains([',', '"', '\n', '\r']) {
            out.push('"');
            out.push_str(&f.replace('"', "\"\""));
            out.push('"');
        } else {
            out.push_str(f);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn quotes_only_where_needed() {
        assert_eq!(super::line(["1.5", "node 1", ""]), "1.5,node 1,");
        assert_eq!(super::line(["a,b", "say \"hi\""]), "\"a,b\",\"say \"\"hi\"\"\"");
    }
}
