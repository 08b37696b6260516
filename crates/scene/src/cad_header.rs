//! What a STEP or IGES file says about itself, read from its text before the kernel sees it: the STEP HEADER
//! section (FILE_DESCRIPTION, FILE_NAME, FILE_SCHEMA) and the IGES global section (the sending system, file
//! name, date, author, organisation). Becomes [`crate::Scene::metadata`]; a field the file leaves empty is left
//! out, and a header that does not parse gives what was read before it.

/// How far into the file the header is looked for.
const HEADER_BYTES: usize = 1 << 16;
/// Longest value kept.
const MAX_VALUE: usize = 256;

#[derive(Debug, PartialEq)]
enum Value {
    Str(String),
    List(Vec<Value>),
    Other,
}

impl Value {
    /// The strings of a value: itself, or a list's (nested lists flattened), the empty ones left out.
    fn strings(&self) -> Vec<String> {
        match self {
            Value::Str(s) if !s.trim().is_empty() => vec![s.trim().to_string()],
            Value::List(v) => v.iter().flat_map(Value::strings).collect(),
            _ => Vec::new(),
        }
    }
}

/// A STEP parameter at `s[*i..]` (ISO 10303-21: 'strings' with '' for a quote, (lists), anything else).
fn step_value(s: &[u8], i: &mut usize, depth: usize) -> Option<Value> {
    while s.get(*i)?.is_ascii_whitespace() {
        *i += 1;
    }
    match s[*i] {
        b'\'' => {
            let mut out = Vec::new();
            *i += 1;
            loop {
                match *s.get(*i)? {
                    b'\'' if s.get(*i + 1) == Some(&b'\'') => {
                        out.push(b'\'');
                        *i += 2;
                    }
                    b'\'' => {
                        *i += 1;
                        break;
                    }
                    c => {
                        out.push(c);
                        *i += 1;
                    }
                }
            }
            Some(Value::Str(String::from_utf8_lossy(&out).into_owned()))
        }
        b'(' if depth < 8 => {
            *i += 1;
            let mut items = Vec::new();
            loop {
                while s.get(*i)?.is_ascii_whitespace() {
                    *i += 1;
                }
                if s[*i] == b')' {
                    *i += 1;
                    return Some(Value::List(items));
                }
                items.push(step_value(s, i, depth + 1)?);
                while s.get(*i)?.is_ascii_whitespace() {
                    *i += 1;
                }
                if s[*i] == b',' {
                    *i += 1;
                }
            }
        }
        _ => {
            while !matches!(*s.get(*i)?, b',' | b')') {
                *i += 1;
            }
            Some(Value::Other)
        }
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn push(out: &mut Vec<(String, String)>, key: &str, values: Vec<String>) {
    let v = values.join("; ");
    if !v.is_empty() {
        out.push((key.to_string(), v.chars().take(MAX_VALUE).collect()));
    }
}

/// The STEP HEADER section's fields.
pub fn step_header(bytes: &[u8]) -> Vec<(String, String)> {
    let bytes = &bytes[..bytes.len().min(HEADER_BYTES)];
    let mut out = Vec::new();
    let Some(start) = find(bytes, b"HEADER;") else {
        return out;
    };
    let section = &bytes[start + 7..];
    let section = &section[..find(section, b"ENDSEC;").unwrap_or(section.len())];
    for (entity, keys) in [
        ("FILE_DESCRIPTION", &["description"][..]),
        (
            "FILE_NAME",
            &[
                "file name",
                "time stamp",
                "author",
                "organization",
                "preprocessor",
                "originating system",
                "authorization",
            ][..],
        ),
        ("FILE_SCHEMA", &["schema"][..]),
    ] {
        let Some(at) = find(section, entity.as_bytes()) else {
            continue;
        };
        let mut i = at + entity.len();
        let Some(Value::List(args)) = step_value(section, &mut i, 0) else {
            continue;
        };
        for (key, arg) in keys.iter().zip(&args) {
            push(&mut out, key, arg.strings());
        }
    }
    out
}

/// The IGES global section's fields (ANSI Y14.26M / IGES 5.3 §2.2.4.3: Hollerith strings `nH…`, the parameter
/// and record delimiters given by its first two fields, ',' and ';' by default).
pub fn iges_header(bytes: &[u8]) -> Vec<(String, String)> {
    let bytes = &bytes[..bytes.len().min(HEADER_BYTES)];
    let mut g = Vec::new();
    for line in bytes.split(|&b| b == b'\n') {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.len() >= 73 && line[72] == b'G' {
            g.extend_from_slice(&line[..72]);
        }
    }
    let fields = iges_fields(&g);
    let mut out = Vec::new();
    for (n, key) in [
        (3, "product"),
        (4, "file name"),
        (5, "native system"),
        (6, "preprocessor"),
        (18, "date"),
        (21, "author"),
        (22, "organization"),
    ] {
        if let Some(v) = fields.get(n - 1) {
            push(&mut out, key, vec![v.trim().to_string()]);
        }
    }
    out
}

/// The global section's fields as text (Hollerith strings unwrapped), up to the record delimiter.
fn iges_fields(g: &[u8]) -> Vec<String> {
    let (mut pd, mut rd) = (b',', b';');
    let mut fields = Vec::new();
    let mut i = 0;
    while i < g.len() && fields.len() < 32 {
        // A Hollerith string: digits, 'H', then that many characters.
        let digits = g[i..].iter().take_while(|c| c.is_ascii_digit()).count();
        let value = if digits > 0 && g.get(i + digits) == Some(&b'H') {
            let n: usize = std::str::from_utf8(&g[i..i + digits])
                .ok()
                .and_then(|d| d.parse().ok())
                .unwrap_or(0);
            let start = i + digits + 1;
            let end = (start + n).min(g.len());
            i = end;
            while i < g.len() && g[i] != pd && g[i] != rd {
                i += 1;
            }
            g[start..end].to_vec()
        } else {
            let start = i;
            while i < g.len() && g[i] != pd && g[i] != rd {
                i += 1;
            }
            g[start..i].to_vec()
        };
        let k = fields.len();
        fields.push(String::from_utf8_lossy(&value).into_owned());
        // The first two fields set the delimiters (empty: the defaults).
        if k == 0 && value.len() == 1 {
            pd = value[0];
        } else if k == 1 && value.len() == 1 {
            rd = value[0];
        }
        match g.get(i) {
            Some(&c) if c == rd && k >= 1 => break,
            Some(_) => i += 1,
            None => break,
        }
    }
    fields
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(v: &[(&str, &str)]) -> Vec<(String, String)> {
        v.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    #[test]
    fn step_header_fields() {
        let file = b"ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('a bracket', ''),'2;1');\n\
            FILE_NAME('bracket.step','2024-03-01T10:00:00',('Ann O''Neil'),('ACME', 'Works'),\n  'ST-DEVELOPER v18',\
            'SolidWorks 2023','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n\
            #1=PRODUCT('not','a header','',());\nENDSEC;\nEND-ISO-10303-21;\n";
        assert_eq!(
            step_header(file),
            pairs(&[
                ("description", "a bracket"),
                ("file name", "bracket.step"),
                ("time stamp", "2024-03-01T10:00:00"),
                ("author", "Ann O'Neil"),
                ("organization", "ACME; Works"),
                ("preprocessor", "ST-DEVELOPER v18"),
                ("originating system", "SolidWorks 2023"),
                ("schema", "AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }"),
            ])
        );
        // Unset ($) and missing fields, a header cut short, no header: what was read.
        let short = b"ISO-10303-21;\nHEADER;\nFILE_NAME('x.stp',$,(''),(''),'pre',";
        assert_eq!(step_header(short), []);
        let unset = b"ISO-10303-21;\nHEADER;\nFILE_NAME('x.stp',$,(''),(''),'pre','sys',$);\nENDSEC;\n";
        assert_eq!(
            step_header(unset),
            pairs(&[
                ("file name", "x.stp"),
                ("preprocessor", "pre"),
                ("originating system", "sys")
            ])
        );
        assert_eq!(step_header(b"garbage"), []);
    }

    #[test]
    fn iges_global_fields() {
        let global =
            "1H,,1H;,7HBRACKET,11Hbracket.igs,12HCATIA V5 R21,8HIGES 5.3,32,38,6,308,15,7HBRACKET,1.0,\
                      2,2HMM,1,0.02,15H20240301.100000,0.001,1000.0,3HAnn,4HACME,11,0,15H20240301.100000;";
        let mut file = format!("{:72}S{:>7}\n", "a bracket", 1);
        for (k, chunk) in global.as_bytes().chunks(72).enumerate() {
            file += &format!("{:72}G{:>7}\n", std::str::from_utf8(chunk).unwrap(), k + 1);
        }
        file += &format!("{:72}D{:>7}\n", "", 1);
        assert_eq!(
            iges_header(file.as_bytes()),
            pairs(&[
                ("product", "BRACKET"),
                ("file name", "bracket.igs"),
                ("native system", "CATIA V5 R21"),
                ("preprocessor", "IGES 5.3"),
                ("date", "20240301.100000"),
                ("author", "Ann"),
                ("organization", "ACME"),
            ])
        );
        // Default delimiters (empty first fields), a comma inside a Hollerith string, and fields left empty.
        let global = ",,9HPART, ONE,,,,;";
        let file = format!("{global:72}G{:>7}\n", 1);
        assert_eq!(iges_header(file.as_bytes()), pairs(&[("product", "PART, ONE")]));
        assert_eq!(iges_header(b"hello"), []);
    }
}
