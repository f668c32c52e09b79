//! Tables whose keys depend on a choice: a material's `model`, a simulation's `integrator`.
//!
//! The Rust type of such a table holds the choice as an externally tagged enum, one variant a
//! struct of the keys only it takes. The file writes those keys beside the table's own, so before
//! serde reads the document, [`split`] moves each key that is not the table's own into a nested
//! table under the chosen variant: `{ model = "xu", energy = "stvk", young = 1e9 }` becomes
//! `{ model = { xu = { energy = "stvk" } }, young = 1e9 }`. Keys keep their spans, so serde
//! refuses a key of another variant with its line and column, and [`Hints`] rewords the refusal
//! to say which variant takes the key.
//!
//! The keys of each variant come from its type (see [`keys_of`] and [`variants_of`]), never from
//! a list kept by hand.

use std::borrow::Cow;
use std::ops::Range;

use serde::de::{self, DeserializeSeed, Deserializer, EnumAccess, VariantAccess, Visitor};
use serde::Deserialize;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// The keys of each variant of a choice: its name and the keys its struct takes.
pub(crate) type Variants = Vec<(&'static str, &'static [&'static str])>;

/// A scene file's tables: serde reads them after `prepare` has split the tables that make a
/// choice. Implemented by the two kinds of scene file; [`crate::parse`] reads either.
pub trait Schema: serde::de::DeserializeOwned + private::Sealed {
    /// Splits the choosing tables of `doc`, and adds what to say when serde refuses a key.
    #[doc(hidden)]
    fn prepare(doc: &mut DeTable<'_>, hints: &mut Hints) -> Result<(), Refusal>;
}

/// Keeps [`Schema`] to this crate's scene files.
pub(crate) mod private {
    /// Implemented by the scene files only.
    pub trait Sealed {}
    impl Sealed for crate::SceneFile {}
    impl Sealed for crate::shell::ShellSceneFile {}
}

/// Where a choice's variant is named.
pub(crate) enum Named {
    /// In the table, under the choice's field; `default` when absent.
    InTable {
        /// The variant when the table does not name one.
        default: &'static str,
    },
    /// Elsewhere in the file (the simulation's model is named by the materials).
    Elsewhere {
        /// The chosen variant.
        variant: String,
        /// Where the file names it, for messages (`"[[material]]"`).
        place: &'static str,
    },
}

/// A choice a table makes: the Rust field that holds it, where it is named and its variants.
pub(crate) struct Choice {
    /// The field (an externally tagged enum); for [`Named::InTable`] also the key naming it.
    pub field: &'static str,
    /// Where the variant is named.
    pub named: Named,
    /// Each variant's keys ([`variants_of`] the field's type).
    pub variants: Variants,
}

/// A problem found while splitting, before serde reads the document.
#[derive(Debug)]
pub struct Refusal {
    /// Where in the text (bytes).
    pub(crate) span: Range<usize>,
    /// What is wrong.
    pub(crate) message: String,
}

/// What to say when serde refuses a value or key: the key's path in the file (from
/// [`Hints::index`]), and for a key that [`split`] moved or [`Hints::foreign`] marked, which
/// choice or kind of scene takes it.
#[derive(Debug, Default)]
pub struct Hints {
    hints: Vec<Hint>,
    paths: Vec<(Range<usize>, String)>,
}

/// What to say of a refused key at `span`.
#[derive(Debug)]
struct Hint {
    span: Range<usize>,
    say: Say,
}

#[derive(Debug)]
enum Say {
    /// Which choice or kind of scene takes the key.
    Note(String),
    /// The key and every key its table takes.
    Expected(String, Vec<&'static str>),
}

impl Hints {
    /// Records the path (`material[1].young`) of every key and value of `doc` as the file
    /// writes them, before [`split`] moves any.
    pub(crate) fn index(&mut self, doc: &DeTable<'_>) {
        self.index_table(doc, "");
    }

    fn index_table(&mut self, table: &DeTable<'_>, prefix: &str) {
        for (k, v) in table.iter() {
            let path = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            self.paths.push((k.span(), path.clone()));
            self.index_value(v, path);
        }
    }

    fn index_value(&mut self, v: &Spanned<DeValue<'_>>, path: String) {
        match v.get_ref() {
            DeValue::Table(t) => self.index_table(t, &path),
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    self.index_value(item, format!("{path}[{i}]"));
                }
            }
            _ => {}
        }
        self.paths.push((v.span(), path));
    }

    /// serde's refusal `message` at `span`, led by the path of the key or value refused; an
    /// unknown key a hint covers says which choice or kind of scene takes it, or else every
    /// key its table takes.
    pub(crate) fn message(&self, span: Option<Range<usize>>, message: &str) -> String {
        let Some(span) = span else {
            return message.to_string();
        };
        let path = self.paths.iter().find(|(s, _)| *s == span).map(|(_, p)| p);
        let message = self.reword(&span, message);
        match path {
            Some(p) => format!("{p}: {message}"),
            None => message,
        }
    }

    fn reword(&self, span: &Range<usize>, message: &str) -> String {
        if !message.starts_with("unknown field") {
            return message.to_string();
        }
        // a key may have a hint of each kind: a note says more than the list
        let at = || self.hints.iter().filter(|h| h.span == *span);
        let note = at().find_map(|h| match &h.say {
            Say::Note(note) => Some(note.clone()),
            Say::Expected(..) => None,
        });
        let listed = || {
            at().find_map(|h| match &h.say {
                Say::Expected(key, expected) => Some(format!(
                    "unknown field `{key}`, expected {}",
                    expected_list(expected)
                )),
                Say::Note(_) => None,
            })
        };
        note.or_else(listed).unwrap_or_else(|| message.to_string())
    }

    /// Marks the keys of `table` that it does not take (`accepted`) but the other kind of scene
    /// does (`foreign`), so that a refusal of one says `note`.
    pub(crate) fn foreign(
        &mut self,
        table: &DeTable<'_>,
        accepted: &[&'static str],
        foreign: &[&'static str],
        note: &str,
    ) {
        for key in table.keys() {
            let k: &str = key.get_ref();
            if !accepted.contains(&k) && foreign.contains(&k) {
                self.hints.push(Hint {
                    span: key.span(),
                    say: Say::Note(format!("a key of {note}")),
                });
            }
        }
    }
}

/// serde's way of listing what a table takes: "`a`", "`a` or `b`", "one of `a`, `b`, `c`".
fn expected_list(keys: &[&str]) -> String {
    match keys {
        [] => "no keys".to_string(),
        [a] => format!("`{a}`"),
        [a, b] => format!("`{a}` or `{b}`"),
        _ => {
            let all: Vec<String> = keys.iter().map(|k| format!("`{k}`")).collect();
            format!("one of {}", all.join(", "))
        }
    }
}

/// Moves the keys of `table` (at `span`) that are not in `own` under the chosen variant of the
/// first choice whose variants take them (the first choice when none does), and returns each
/// choice's chosen variant with where it is named. `own` holds the choices' fields.
pub(crate) fn split(
    table: &mut DeTable<'_>,
    span: Range<usize>,
    own: &[&'static str],
    choices: &[Choice],
    hints: &mut Hints,
) -> Result<Vec<Spanned<String>>, Refusal> {
    let mut chosen = Vec::with_capacity(choices.len());
    let mut named_at = Vec::with_capacity(choices.len());
    for c in choices {
        let (variant, at) = match &c.named {
            Named::InTable { default } => match table.remove(c.field) {
                None => (default.to_string(), span.clone()),
                Some(v) => match v.get_ref() {
                    DeValue::String(s) => (s.to_string(), v.span()),
                    _ => {
                        let names: Vec<&str> = c.variants.iter().map(|(n, _)| *n).collect();
                        return Err(Refusal {
                            span: v.span(),
                            message: format!(
                                "`{}` must be a string: {}",
                                c.field,
                                expected_list(&names)
                            ),
                        });
                    }
                },
            },
            Named::Elsewhere { variant, .. } => (variant.clone(), span.clone()),
        };
        chosen.push(variant);
        named_at.push(at);
    }
    // The table's own keys, less the choices, and each chosen variant's: what it takes.
    let elsewhere = |k: &str| {
        choices
            .iter()
            .any(|c| c.field == k && matches!(c.named, Named::Elsewhere { .. }))
    };
    let mut expected: Vec<&'static str> = own.iter().copied().filter(|k| !elsewhere(k)).collect();
    for (c, v) in choices.iter().zip(&chosen) {
        expected.extend(keys_of_variant(&c.variants, v));
    }
    let moved: Vec<Spanned<Cow<'_, str>>> = table
        .keys()
        .filter(|k| {
            let k: &str = k.get_ref();
            !own.contains(&k) || elsewhere(k)
        })
        .cloned()
        .collect();
    let mut inner: Vec<DeTable<'_>> = choices.iter().map(|_| DeTable::new()).collect();
    for key in moved {
        let name: &str = key.get_ref();
        let at = choices
            .iter()
            .position(|c| c.field == name)
            .or_else(|| {
                choices
                    .iter()
                    .position(|c| c.variants.iter().any(|(_, keys)| keys.contains(&name)))
            })
            .unwrap_or(0);
        let Some(c) = choices.get(at) else { break };
        if !keys_of_variant(&c.variants, &chosen[at]).contains(&name) {
            let other = c
                .variants
                .iter()
                .find(|(_, keys)| keys.contains(&name))
                .map(|(v, _)| *v);
            let place = match &c.named {
                Named::InTable { .. } => None,
                Named::Elsewhere { place, .. } => Some(*place),
            };
            let note = match (other, place) {
                (Some(o), None) => Some(format!(
                    "a key of {f} = \"{o}\"; this table's {f} is \"{}\"",
                    chosen[at],
                    f = c.field
                )),
                (Some(o), Some(p)) => Some(format!(
                    "a key of {f} = \"{o}\"; the {f} of {p} is \"{}\"",
                    chosen[at],
                    f = c.field
                )),
                (None, Some(p)) if name == c.field => Some(format!("named in {p}")),
                _ => None,
            };
            hints.hints.push(Hint {
                span: key.span(),
                say: match note {
                    Some(note) => Say::Note(note),
                    None => Say::Expected(name.to_string(), expected.clone()),
                },
            });
        }
        if let Some((k, v)) = table.remove_entry(name) {
            inner[at].insert(k, v);
        }
    }
    let mut out = Vec::with_capacity(choices.len());
    for ((c, variant), (keys, at)) in choices
        .iter()
        .zip(chosen)
        .zip(inner.into_iter().zip(named_at))
    {
        let mut outer = DeTable::new();
        outer.insert(
            Spanned::new(at.clone(), Cow::Owned(variant.clone())),
            Spanned::new(at.clone(), DeValue::Table(keys)),
        );
        table.insert(
            Spanned::new(at.clone(), Cow::Borrowed(c.field)),
            Spanned::new(at.clone(), DeValue::Table(outer)),
        );
        out.push(Spanned::new(at, variant));
    }
    Ok(out)
}

/// A table's own keys and the keys of every variant of its choices: all it may take.
pub(crate) fn all_keys(own: &[&'static str], choices: &[&Variants]) -> Vec<&'static str> {
    let mut keys = own.to_vec();
    for v in choices {
        for (_, k) in v.iter() {
            keys.extend(k.iter().filter(|k| !keys.contains(k)).collect::<Vec<_>>());
        }
    }
    keys
}

/// The keys of `variant` among `variants` (none for a name that is not one: serde refuses it).
fn keys_of_variant(variants: &Variants, variant: &str) -> &'static [&'static str] {
    variants
        .iter()
        .find(|(v, _)| *v == variant)
        .map_or(&[], |(_, keys)| *keys)
}

/// The table `key` of `doc` with its span.
pub(crate) fn table_mut<'a, 'i>(
    doc: &'a mut DeTable<'i>,
    key: &str,
) -> Option<(&'a mut DeTable<'i>, Range<usize>)> {
    let v = doc.get_mut(key)?;
    let span = v.span();
    match v.get_mut() {
        DeValue::Table(t) => Some((t, span)),
        _ => None,
    }
}

/// The tables of the array of tables `key` of `doc`, each with its span.
pub(crate) fn tables_mut<'a, 'i>(
    doc: &'a mut DeTable<'i>,
    key: &str,
) -> Vec<(&'a mut DeTable<'i>, Range<usize>)> {
    let Some(v) = doc.get_mut(key) else {
        return Vec::new();
    };
    let DeValue::Array(items) = v.get_mut() else {
        return Vec::new();
    };
    items
        .iter_mut()
        .filter_map(|item| {
            let span = item.span();
            match item.get_mut() {
                DeValue::Table(t) => Some((t, span)),
                _ => None,
            }
        })
        .collect()
}

/// The keys the struct `T` takes.
pub(crate) fn keys_of<T: for<'de> Deserialize<'de>>() -> &'static [&'static str] {
    let mut found = Found::default();
    let _ = T::deserialize(Probe {
        found: &mut found,
        pick: None,
    });
    found.fields
}

/// The variants of the enum `T`, each with the keys of its struct.
pub(crate) fn variants_of<T: for<'de> Deserialize<'de>>() -> Variants {
    let mut found = Found::default();
    let _ = T::deserialize(Probe {
        found: &mut found,
        pick: None,
    });
    let names = found.variants;
    (0..names.len())
        .map(|i| {
            let mut found = Found::default();
            let _ = T::deserialize(Probe {
                found: &mut found,
                pick: Some(i),
            });
            (names[i], found.fields)
        })
        .collect()
}

/// What a probe saw of a type.
#[derive(Default)]
struct Found {
    fields: &'static [&'static str],
    variants: &'static [&'static str],
}

/// A deserializer that records the struct fields or enum variants a type asks for and then
/// stops; with `pick`, it enters that variant and records its fields.
struct Probe<'a> {
    found: &'a mut Found,
    pick: Option<usize>,
}

/// How a probe stops.
type Stop = de::value::Error;

fn stop() -> Stop {
    de::Error::custom("probed")
}

impl<'de> Deserializer<'de> for Probe<'_> {
    type Error = Stop;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Stop> {
        Err(stop())
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        fields: &'static [&'static str],
        _: V,
    ) -> Result<V::Value, Stop> {
        self.found.fields = fields;
        Err(stop())
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Stop> {
        self.found.variants = variants;
        match self.pick {
            Some(i) if i < variants.len() => visitor.visit_enum(Pick {
                found: self.found,
                name: variants[i],
            }),
            _ => Err(stop()),
        }
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map identifier
        ignored_any
    }
}

/// The variant a probe enters.
struct Pick<'a> {
    found: &'a mut Found,
    name: &'static str,
}

impl<'de, 'a> EnumAccess<'de> for Pick<'a> {
    type Error = Stop;
    type Variant = Pick<'a>;

    fn variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<(S::Value, Self), Stop> {
        let v = seed.deserialize(de::value::StrDeserializer::<Stop>::new(self.name))?;
        Ok((v, self))
    }
}

impl<'de> VariantAccess<'de> for Pick<'_> {
    type Error = Stop;

    fn unit_variant(self) -> Result<(), Stop> {
        Ok(())
    }

    fn newtype_variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<S::Value, Stop> {
        seed.deserialize(Probe {
            found: self.found,
            pick: None,
        })
    }

    fn tuple_variant<V: Visitor<'de>>(self, _: usize, _: V) -> Result<V::Value, Stop> {
        Err(stop())
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        _: V,
    ) -> Result<V::Value, Stop> {
        self.found.fields = fields;
        Err(stop())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct A {
        a: Option<f64>,
    }

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct B {
        b: Option<f64>,
    }

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(rename_all = "snake_case")]
    enum Kind {
        First(A),
        Second(B),
    }

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Table {
        x: f64,
        kind: Kind,
    }

    fn parse(text: &str) -> Result<Table, String> {
        let mut doc = DeTable::parse(text).map_err(|e| e.to_string())?;
        let span = doc.span();
        let mut hints = Hints::default();
        hints.index(doc.get_ref());
        let choice = Choice {
            field: "kind",
            named: Named::InTable { default: "first" },
            variants: variants_of::<Kind>(),
        };
        split(
            doc.get_mut(),
            span,
            keys_of::<Table>(),
            &[choice],
            &mut hints,
        )
        .map_err(|r| r.message)?;
        Table::deserialize(toml::de::Deserializer::from(doc)).map_err(|e| {
            let at = e.span().map(|s| text[s].to_string()).unwrap_or_default();
            format!("{at}: {}", hints.message(e.span(), e.message()))
        })
    }

    #[test]
    fn probes_read_the_keys_from_the_types() {
        assert_eq!(keys_of::<Table>(), &["x", "kind"]);
        assert_eq!(
            variants_of::<Kind>(),
            vec![("first", &["a"][..]), ("second", &["b"][..])]
        );
    }

    #[test]
    fn a_variants_keys_go_to_its_struct() {
        let t = parse("x = 1.0\nb = 2.0\nkind = \"second\"\n").unwrap();
        assert_eq!(t.kind, Kind::Second(B { b: Some(2.0) }));
        let t = parse("x = 1.0\na = 3.0\n").unwrap();
        assert_eq!(t.kind, Kind::First(A { a: Some(3.0) }));
    }

    #[test]
    fn another_variants_key_is_refused_at_the_key() {
        let e = parse("x = 1.0\nb = 2.0\n").unwrap_err();
        assert_eq!(
            e,
            "b: b: a key of kind = \"second\"; this table's kind is \"first\""
        );
        let e = parse("x = 1.0\nzz = 2.0\n").unwrap_err();
        assert_eq!(
            e,
            "zz: zz: unknown field `zz`, expected one of `x`, `kind`, `a`"
        );
        let e = parse("x = 1.0\nkind = \"third\"\n").unwrap_err();
        assert!(
            e.starts_with("\"third\": kind: unknown variant `third`"),
            "{e}"
        );
        let e = parse("x = 1.0\nkind = 3\n").unwrap_err();
        assert_eq!(e, "`kind` must be a string: `first` or `second`");
    }
}
