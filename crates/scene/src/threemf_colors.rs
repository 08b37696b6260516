//! 3MF colours, read from the model parts' XML (the threemf crate parses none of them): the core spec's
//! `<basematerials>` (each `<base displaycolor="#RRGGBB[AA]">`) and the materials extension's `<colorgroup>`
//! (each `<color color="#RRGGBB[AA]">`), whatever their namespace prefix. An object's colour is its own property
//! (`pid` + `pindex`), else its first triangle's (`pid` + `p1`, or the object's `pid` with `p1`); a mesh has one
//! colour here (per-triangle colours beyond the first are not kept). Colours are sRGB in the file, linear in the
//! scene, as glTF's base colour.
use std::collections::HashMap;
use std::io::BufRead;

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

/// Property groups (by id: their colours) and what each object refers to.
#[derive(Default)]
pub(crate) struct Colors {
    groups: HashMap<usize, Vec<[f32; 4]>>,
    /// Object id → (its pid, its pindex, its first triangle's pid and p1).
    objects: HashMap<usize, ObjectProps>,
}

#[derive(Default, Clone, Copy)]
struct ObjectProps {
    pid: Option<usize>,
    pindex: Option<usize>,
    first_triangle: Option<(Option<usize>, usize)>,
}

fn attr(e: &BytesStart, name: &str) -> Option<String> {
    e.attributes()
        .flatten()
        .find(|a| a.key.local_name().as_ref() == name)
        .map(|a| a.value.into_owned())
}

fn number(e: &BytesStart, name: &str) -> Option<usize> {
    attr(e, name).and_then(|v| v.trim().parse().ok())
}

/// `#RRGGBB` or `#RRGGBBAA` (sRGB) as linear RGBA.
pub fn parse_color(s: &str) -> Option<[f32; 4]> {
    let hex = s.trim().strip_prefix('#')?;
    if !(hex.len() == 6 || hex.len() == 8) || !hex.is_ascii() {
        return None;
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
    let linear = |b: u8| {
        let c = b as f32 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let a = if hex.len() == 8 {
        byte(6)? as f32 / 255.0
    } else {
        1.0
    };
    Some([linear(byte(0)?), linear(byte(2)?), linear(byte(4)?), a])
}

impl Colors {
    /// Reads one model part's XML as a stream (one event held at a time).
    pub(crate) fn read(&mut self, xml: impl BufRead) -> Result<(), String> {
        let mut reader = Reader::from_reader(xml);
        let mut buf = Vec::new();
        // The group being read (its id) and the object being read.
        let mut group: Option<usize> = None;
        let mut object: Option<usize> = None;
        loop {
            buf.clear();
            let event = reader
                .read_event_into(&mut buf)
                .map_err(|e| format!("model XML at byte {}: {e}", reader.buffer_position()))?;
            match event {
                Event::Start(e) | Event::Empty(e) => match e.local_name().as_ref() {
                    "basematerials" | "colorgroup" => {
                        group = number(&e, "id");
                        if let Some(id) = group {
                            self.groups.entry(id).or_default();
                        }
                    }
                    "base" | "color" => {
                        let key: &str = if e.local_name().as_ref() == "base" {
                            "displaycolor"
                        } else {
                            "color"
                        };
                        if let (Some(id), Some(c)) = (group, attr(&e, key).and_then(|v| parse_color(&v))) {
                            self.groups.entry(id).or_default().push(c);
                        }
                    }
                    "object" => {
                        object = number(&e, "id");
                        if let Some(id) = object {
                            self.objects.insert(
                                id,
                                ObjectProps {
                                    pid: number(&e, "pid"),
                                    pindex: number(&e, "pindex"),
                                    first_triangle: None,
                                },
                            );
                        }
                    }
                    "triangle" => {
                        if let Some(props) = object.and_then(|id| self.objects.get_mut(&id)) {
                            if props.first_triangle.is_none() {
                                if let Some(p1) = number(&e, "p1") {
                                    props.first_triangle = Some((number(&e, "pid"), p1));
                                }
                            }
                        }
                    }
                    _ => {}
                },
                Event::End(e) => match e.local_name().as_ref() {
                    "basematerials" | "colorgroup" => group = None,
                    "object" => object = None,
                    _ => {}
                },
                Event::Eof => return Ok(()),
                _ => {}
            }
        }
    }

    /// Each object's linear RGBA colour, by object id, for the objects whose colour the file gives.
    pub(crate) fn by_object(&self) -> HashMap<usize, [f32; 4]> {
        let color = |pid: Option<usize>, index: Option<usize>| -> Option<[f32; 4]> {
            self.groups.get(&pid?)?.get(index?).copied()
        };
        self.objects
            .iter()
            .filter_map(|(&id, p)| {
                let own = color(p.pid, p.pindex);
                let first = p
                    .first_triangle
                    .and_then(|(pid, p1)| color(pid.or(p.pid), Some(p1)));
                own.or(first).map(|c| (id, c))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_of_objects_from_base_materials_colour_groups_and_triangles() {
        let xml = r##"<model xmlns:m="http://schemas.microsoft.com/3dmanufacturing/material/2015/02">
          <resources>
            <basematerials id="1"><base name="red" displaycolor="#FF0000"/><base name="grey" displaycolor="#808080FF"/></basematerials>
            <m:colorgroup id="5"><m:color color="#0000FF80"/></m:colorgroup>
            <object id="2" pid="1" pindex="1"><mesh><triangles><triangle v1="0" v2="1" v3="2" pid="5" p1="0"/></triangles></mesh></object>
            <object id="3"><mesh><triangles><triangle v1="0" v2="1" v3="2" pid="5" p1="0"/></triangles></mesh></object>
            <object id="4" pid="1"><mesh><triangles><triangle v1="0" v2="1" v3="2" p1="0"/></triangles></mesh></object>
            <object id="6"><mesh><triangles><triangle v1="0" v2="1" v3="2"/></triangles></mesh></object>
            <object id="7" pid="9" pindex="0"/>
          </resources></model>"##;
        let mut c = Colors::default();
        c.read(xml.as_bytes()).unwrap();
        let by = c.by_object();
        // The object's own property first; sRGB 0x80 is linear 0.216.
        let grey = by[&2];
        assert!((grey[0] - 0.2158).abs() < 1e-3 && grey[3] == 1.0, "{grey:?}");
        // Else its first triangle's, through the triangle's group or the object's.
        assert_eq!(by[&3], [0.0, 0.0, 1.0, 128.0 / 255.0]);
        assert_eq!(by[&4], [1.0, 0.0, 0.0, 1.0]);
        // No colour, or a group that does not exist: none.
        assert!(!by.contains_key(&6) && !by.contains_key(&7));
        assert_eq!(parse_color("#12345"), None);
        assert_eq!(parse_color("#GG0000"), None);
        assert!(
            c.read("<model><object id='1'></model>".as_bytes()).is_err(),
            "mismatched tags"
        );
    }
}
