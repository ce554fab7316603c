//! A line-oriented INI reader that keeps line numbers.
//!
//! Written by hand because the INI crates drop line numbers, merge duplicate
//! keys silently and disagree on comments; CiA 306 files from vendors need
//! all three handled explicitly (errors must name the line).

use std::collections::BTreeMap;

/// One `key=value` with the line it came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    /// Key as written.
    pub key: String,
    /// Value, trimmed.
    pub value: String,
    /// 1-based line number.
    pub line: usize,
}

/// One `[section]` with its entries in file order.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Section {
    /// Name as written (without brackets).
    pub name: String,
    /// 1-based line of the header.
    pub line: usize,
    /// Entries in file order.
    pub entries: Vec<Entry>,
    index: BTreeMap<String, usize>,
}

impl Section {
    /// Value of `key` (case-insensitive).
    pub fn get(&self, key: &str) -> Option<&Entry> {
        self.index.get(&key.to_ascii_lowercase()).map(|&i| &self.entries[i])
    }
}

/// A parsed file: sections by lower-case name, plus problems found.
#[derive(Clone, Debug, Default)]
pub struct Ini {
    /// Sections keyed by lower-case name, in file order of first appearance.
    pub sections: Vec<Section>,
    by_name: BTreeMap<String, usize>,
    /// Recoverable oddities: (line, message).
    pub warnings: Vec<(usize, String)>,
}

impl Ini {
    /// Section by name (case-insensitive).
    pub fn section(&self, name: &str) -> Option<&Section> {
        self.by_name.get(&name.to_ascii_lowercase()).map(|&i| &self.sections[i])
    }

    /// Parse text. Lines outside a section, lines without `=` and duplicate
    /// keys are warnings; the first value of a duplicate key wins, the same
    /// as most CANopen tools.
    pub fn parse(text: &str) -> Ini {
        let mut ini = Ini::default();
        let mut current: Option<usize> = None;
        for (n, raw) in text.lines().enumerate() {
            let line = n + 1;
            let s = raw.trim_start_matches('\u{feff}').trim();
            if s.is_empty() || s.starts_with(';') || s.starts_with('#') {
                continue;
            }
            if let Some(rest) = s.strip_prefix('[') {
                let Some(end) = rest.find(']') else {
                    ini.warnings.push((line, format!("section header without ']': {s}")));
                    current = None;
                    continue;
                };
                let name = rest[..end].trim().to_string();
                let key = name.to_ascii_lowercase();
                current = Some(match ini.by_name.get(&key) {
                    Some(&i) => {
                        ini.warnings.push((line, format!("section [{name}] repeated; entries merged")));
                        i
                    }
                    None => {
                        ini.sections.push(Section { name, line, ..Section::default() });
                        ini.by_name.insert(key, ini.sections.len() - 1);
                        ini.sections.len() - 1
                    }
                });
                continue;
            }
            let Some(eq) = s.find('=') else {
                ini.warnings.push((line, format!("line ignored, no '=': {s}")));
                continue;
            };
            let Some(ci) = current else {
                ini.warnings.push((line, "entry outside any section ignored".to_string()));
                continue;
            };
            let key = s[..eq].trim().to_string();
            // CiA 306 has whole-line comments only: a ';' inside a value is data.
            let value = s[eq + 1..].trim();
            let sec = &mut ini.sections[ci];
            let lk = key.to_ascii_lowercase();
            if sec.index.contains_key(&lk) {
                ini.warnings.push((line, format!("duplicate key {key} in [{}]; first value kept", sec.name)));
                continue;
            }
            sec.index.insert(lk, sec.entries.len());
            sec.entries.push(Entry { key, value: value.to_string(), line });
        }
        ini
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_lines_and_tolerates_noise() {
        let ini =
            Ini::parse("; c\n\u{feff}[FileInfo]\nFileName = a.eds\n junk\n[fileinfo]\nfilename=b\nX=1\n");
        let s = ini.section("FILEINFO").unwrap();
        assert_eq!(s.get("filename").unwrap().value, "a.eds");
        assert_eq!(s.get("FileName").unwrap().line, 3);
        assert_eq!(s.get("x").unwrap().line, 7);
        assert_eq!(ini.warnings.len(), 3, "{:?}", ini.warnings);
    }
}
