//! The XML layer: a small writer over `quick-xml`'s event writer (which
//! does the escaping), and an element tree read with `quick-xml`'s pull
//! reader, for the ESI reader and the validator.

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, BytesText, Event};

/// An indenting XML writer into memory. Writing into a `Vec` cannot fail,
/// so the `io::Result`s of `quick-xml` are dropped.
pub struct XmlWriter {
    w: Writer<Vec<u8>>,
}

impl XmlWriter {
    /// A document with the XML declaration (UTF-8), indented by two spaces.
    pub fn new() -> XmlWriter {
        let mut w = Writer::new_with_indent(Vec::with_capacity(64 * 1024), b' ', 2);
        let _ = w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)));
        XmlWriter { w }
    }

    /// `<name a="v" …>`.
    pub fn open(&mut self, name: &str, attrs: &[(&str, &str)]) {
        let _ =
            self.w.write_event(Event::Start(BytesStart::new(name).with_attributes(attrs.iter().copied())));
    }

    /// `</name>`.
    pub fn close(&mut self, name: &str) {
        let _ = self.w.write_event(Event::End(BytesEnd::new(name)));
    }

    /// `<name a="v" …>text</name>` on one line (text escaped).
    pub fn leaf(&mut self, name: &str, attrs: &[(&str, &str)], text: &str) {
        let _ = self
            .w
            .create_element(name)
            .with_attributes(attrs.iter().copied())
            .write_text_content(BytesText::new(text));
    }

    /// `<name>text</name>`.
    pub fn text(&mut self, name: &str, text: &str) {
        self.leaf(name, &[], text);
    }

    /// `<name a="v" …/>`.
    pub fn empty(&mut self, name: &str, attrs: &[(&str, &str)]) {
        let _ =
            self.w.write_event(Event::Empty(BytesStart::new(name).with_attributes(attrs.iter().copied())));
    }

    /// The document, ending with a newline.
    pub fn finish(self) -> String {
        let mut s = String::from_utf8_lossy(&self.w.into_inner()).into_owned();
        s.push('\n');
        s
    }
}

impl Default for XmlWriter {
    fn default() -> Self {
        XmlWriter::new()
    }
}

/// One element of a parsed document.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Element {
    /// Tag name.
    pub name: String,
    /// Attributes in document order, values unescaped.
    pub attrs: Vec<(String, String)>,
    /// Child elements in document order.
    pub children: Vec<Element>,
    /// Character data directly inside, unescaped, not trimmed.
    pub text: String,
}

impl Element {
    /// An attribute value.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }
    /// The first child with this name.
    pub fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }
    /// Every child with this name.
    pub fn all<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
    /// The text of the first child with this name.
    pub fn child_text(&self, name: &str) -> Option<&str> {
        self.child(name).map(|c| c.text.as_str())
    }
}

/// Why a document could not be read as XML.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct XmlError {
    /// Byte position in the input.
    pub position: u64,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for XmlError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "XML error at byte {}: {}", self.position, self.message)
    }
}

impl std::error::Error for XmlError {}

/// Nesting deeper than this is refused (ESI files nest about 10 deep);
/// it bounds memory and recursion for hostile input.
const MAX_DEPTH: usize = 64;

/// Parse a document into its root element: well-formed XML 1.0 (matching
/// end tags, one root, known entities), comments, processing instructions
/// and the declaration skipped.
pub fn parse(text: &str) -> Result<Element, XmlError> {
    let mut reader = quick_xml::Reader::from_str(text);
    let err =
        |r: &quick_xml::Reader<&[u8]>, m: String| XmlError { position: r.buffer_position(), message: m };
    let mut stack: Vec<Element> = Vec::new();
    let mut root: Option<Element> = None;
    loop {
        let ev = reader.read_event().map_err(|e| err(&reader, e.to_string()))?;
        match ev {
            Event::Start(s) | Event::Empty(s) if root.is_some() && stack.is_empty() => {
                let _ = s;
                return Err(err(&reader, "content after the root element".into()));
            }
            Event::Start(s) => {
                if stack.len() >= MAX_DEPTH {
                    return Err(err(&reader, format!("nested deeper than {MAX_DEPTH}")));
                }
                stack.push(start(&s).map_err(|m| err(&reader, m))?);
            }
            Event::Empty(s) => {
                let e = start(&s).map_err(|m| err(&reader, m))?;
                match stack.last_mut() {
                    Some(p) => p.children.push(e),
                    None => root = Some(e),
                }
            }
            Event::End(_) => {
                let Some(e) = stack.pop() else { return Err(err(&reader, "unmatched end tag".into())) };
                match stack.last_mut() {
                    Some(p) => p.children.push(e),
                    None => root = Some(e),
                }
            }
            Event::Text(t) => match stack.last_mut() {
                Some(p) => p.text.push_str(&t.xml10_content()),
                None if t.xml10_content().trim().is_empty() => {}
                None => return Err(err(&reader, "text outside the root element".into())),
            },
            Event::CData(c) => match stack.last_mut() {
                Some(p) => p.text.push_str(&c.into_inner()),
                None => return Err(err(&reader, "CDATA outside the root element".into())),
            },
            Event::GeneralRef(r) => {
                let c = entity(&r).ok_or_else(|| err(&reader, format!("unknown entity &{};", &*r)))?;
                match stack.last_mut() {
                    Some(p) => p.text.push_str(&c),
                    None => return Err(err(&reader, "entity outside the root element".into())),
                }
            }
            Event::Eof => break,
            Event::Decl(_) | Event::PI(_) | Event::Comment(_) | Event::DocType(_) => {}
        }
    }
    if !stack.is_empty() {
        return Err(err(&reader, format!("<{}> is not closed", stack[stack.len() - 1].name)));
    }
    root.ok_or_else(|| err(&reader, "no root element".into()))
}

fn start(s: &BytesStart<'_>) -> Result<Element, String> {
    let mut e = Element { name: s.name().as_ref().to_string(), ..Element::default() };
    for a in s.attributes() {
        let a = a.map_err(|x| x.to_string())?;
        let v = a.normalized_value(quick_xml::XmlVersion::Implicit1_0).map_err(|x| x.to_string())?;
        e.attrs.push((a.key.as_ref().to_string(), v.into_owned()));
    }
    Ok(e)
}

/// A character reference or one of the five predefined entities.
fn entity(r: &quick_xml::events::BytesRef<'_>) -> Option<String> {
    if r.is_char_ref() {
        return r.resolve_char_ref().ok().flatten().map(String::from);
    }
    Some(
        match &**r {
            "amp" => "&",
            "lt" => "<",
            "gt" => ">",
            "quot" => "\"",
            "apos" => "'",
            _ => return None,
        }
        .to_string(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_escaped_and_parses_back() {
        let mut w = XmlWriter::new();
        w.open("Root", &[("Version", "1.6")]);
        w.leaf("Name", &[("LcId", "1033")], "A & B <c> \"d\" 'e'");
        w.empty("Flag", &[("x", "<&>")]);
        w.close("Root");
        let s = w.finish();
        assert!(s.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Root Version=\"1.6\">\n  <Name"));
        let root = parse(&s).unwrap();
        assert_eq!(root.name, "Root");
        assert_eq!(root.child_text("Name"), Some("A & B <c> \"d\" 'e'"));
        assert_eq!(root.child("Flag").and_then(|f| f.attr("x")), Some("<&>"));
    }

    #[test]
    fn refuses_what_is_not_well_formed() {
        for bad in
            ["", "<a>", "<a></b>", "<a/><b/>", "<a>&foo;</a>", "x<a/>", "<a x='1' x='2'/>", "<a><b></a>"]
        {
            assert!(parse(bad).is_err(), "{bad:?}");
        }
        let deep = "<a>".repeat(MAX_DEPTH + 1) + &"</a>".repeat(MAX_DEPTH + 1);
        assert!(parse(&deep).is_err());
        let ok = parse("<!-- c --><a>&#x41;&#66;<![CDATA[<x>]]></a>").unwrap();
        assert_eq!(ok.text, "AB<x>");
    }
}
