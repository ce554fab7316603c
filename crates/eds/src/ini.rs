//! A line-oriented INI reader that keeps line numbers.
//!
//! Written by hand because the INI crates drop line numbers, merge duplicate
//! keys silently and disagree on comments; CiA 306 files from vendors need
//! all three handled explicitly (errors must name the line).

use std::collections::BTreeMap;

/// One `key=value` with the line it came from, borrowed from the text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IniEntry<'a> {
    /// Key as written.
    pub key: &'a str,
    /// Value, trimmed.
    pub value: &'a str,
    /// 1-based line number.
    pub line: usize,
}

/// Sections up to this many entries are searched by scanning; larger ones
/// (a hostile file's) get an index. A CiA 306 section has about ten keys,
/// and a scan costs less than lower-casing the key for a map lookup.
const SCAN: usize = 16;

/// One `[section]` with its entries in file order.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Section<'a> {
    /// Name as written (without brackets).
    pub name: &'a str,
    /// 1-based line of the header.
    pub line: usize,
    /// Entries in file order.
    pub entries: Vec<IniEntry<'a>>,
    /// Lower-case key → position; filled only past [`SCAN`] entries.
    index: BTreeMap<String, usize>,
}

impl<'a> Section<'a> {
    /// Value of `key` (case-insensitive).
    pub fn get(&self, key: &str) -> Option<&IniEntry<'a>> {
        self.position(key).map(|i| &self.entries[i])
    }

    fn position(&self, key: &str) -> Option<usize> {
        if self.entries.len() <= SCAN {
            self.entries.iter().position(|e| e.key.eq_ignore_ascii_case(key))
        } else {
            self.index.get(&key.to_ascii_lowercase()).copied()
        }
    }

    fn push(&mut self, e: IniEntry<'a>) {
        self.entries.push(e);
        let n = self.entries.len();
        if n == SCAN + 1 {
            for (i, e) in self.entries.iter().enumerate() {
                self.index.insert(e.key.to_ascii_lowercase(), i);
            }
        } else if n > SCAN + 1 {
            self.index.insert(self.entries[n - 1].key.to_ascii_lowercase(), n - 1);
        }
    }
}

/// A parsed file: sections by lower-case name, plus problems found.
#[derive(Clone, Debug, Default)]
pub struct Ini<'a> {
    /// Sections keyed by lower-case name, in file order of first appearance.
    pub sections: Vec<Section<'a>>,
    by_name: BTreeMap<String, usize>,
    /// Recoverable oddities: (line, message).
    pub warnings: Vec<(usize, String)>,
    /// Malformed lines that lose data (a section header that does not
    /// close: its entries would land nowhere): (line, message).
    pub errors: Vec<(usize, String)>,
}

impl<'a> Ini<'a> {
    /// Section by name (case-insensitive).
    pub fn section(&self, name: &str) -> Option<&Section<'a>> {
        self.by_name.get(&name.to_ascii_lowercase()).map(|&i| &self.sections[i])
    }

    /// Parse text. Lines outside a section, lines without `=` and duplicate
    /// keys are warnings; the first value of a duplicate key wins, the same
    /// as most CANopen tools.
    pub fn parse(text: &'a str) -> Ini<'a> {
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
                    ini.errors.push((line, format!("section header without ']': {s}")));
                    current = None;
                    continue;
                };
                if !rest[end + 1..].trim().is_empty() {
                    ini.errors.push((line, format!("text after the section header's ']': {s}")));
                }
                let name = rest[..end].trim();
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
            let key = s[..eq].trim();
            // CiA 306 has whole-line comments only: a ';' inside a value is data.
            let value = s[eq + 1..].trim();
            let sec = &mut ini.sections[ci];
            if sec.position(key).is_some() {
                ini.warnings.push((line, format!("duplicate key {key} in [{}]; first value kept", sec.name)));
                continue;
            }
            sec.push(IniEntry { key, value, line });
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

    #[test]
    fn large_sections_are_indexed_and_keep_the_first_value() {
        let mut text = String::from("[S]\n");
        for i in 0..40 {
            text.push_str(&format!("Key{i}={i}\n"));
        }
        text.push_str("KEY3=dup\nkey39=dup\n");
        let ini = Ini::parse(&text);
        let s = ini.section("s").unwrap();
        assert_eq!(s.entries.len(), 40);
        for i in 0..40 {
            assert_eq!(s.get(&format!("kEy{i}")).unwrap().value, i.to_string());
        }
        assert!(s.get("key40").is_none());
        assert_eq!(ini.warnings.len(), 2, "{:?}", ini.warnings);
    }
}
