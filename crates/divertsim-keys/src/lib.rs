//! `#[derive(Keys)]`: one declaration per scenario key.
//!
//! A section of the scenario file is a struct whose fields are its keys. Each field carries
//! its help text (the doc comment, which becomes the schema's description), and with this
//! derive its default and its allowed range in one attribute beside it:
//!
//! ```ignore
//! #[derive(Keys)]
//! #[keys(section = "machine", default)]
//! pub struct MachineConfig {
//!     /// P_max: belt width [m].
//!     #[key(default = 0.7, range = Bound::closed(0.01, 10.0, "m").because("…"))]
//!     pub belt_width: f64,
//! }
//! ```
//!
//! From that the derive writes:
//! - `impl Default` (with `#[keys(default)]`): each field's `default = …`, or
//!   `Default::default()` where none is given;
//! - for each `range = …`, an associated constant `BELT_WIDTH: Bound` keyed by its path in
//!   the file (`machine.belt_width`; `at = "[][0]"` for a part of the value, with
//!   `name = …` for the constant), and `BOUNDS`, every range of the section.
//!
//! The api's `config::SECTIONS` gathers every section's `BOUNDS`: validation checks each
//! value by its key path, and the schema (`minimum`/`maximum`, the description's
//! "Allowed: …" and "Default …") and `divertsim example` are written from them. The
//! expanded code names `crate::config::bounds::Bound`, so the derive serves divertsim-api
//! alone.

use proc_macro::TokenStream;
use quote::{format_ident, quote};
use syn::ext::IdentExt;
use syn::{parse_macro_input, Data, DeriveInput, Expr, Fields, Ident, LitStr};

/// See the crate's documentation.
#[proc_macro_derive(Keys, attributes(keys, key))]
pub fn derive_keys(input: TokenStream) -> TokenStream {
    let input = parse_macro_input!(input as DeriveInput);
    match expand(&input) {
        Ok(t) => t.into(),
        Err(e) => e.to_compile_error().into(),
    }
}

/// One `range = …` of a field.
struct Range {
    name: Ident,
    key: String,
    bound: Expr,
}

fn expand(input: &DeriveInput) -> syn::Result<proc_macro2::TokenStream> {
    let mut section: Option<String> = None;
    let mut want_default = false;
    for attr in input.attrs.iter().filter(|a| a.path().is_ident("keys")) {
        attr.parse_nested_meta(|meta| {
            if meta.path.is_ident("section") {
                section = Some(meta.value()?.parse::<LitStr>()?.value());
                Ok(())
            } else if meta.path.is_ident("default") {
                want_default = true;
                Ok(())
            } else {
                Err(meta.error("expected `section = \"…\"` or `default`"))
            }
        })?;
    }
    if !input.generics.params.is_empty() {
        return Err(syn::Error::new_spanned(
            &input.generics,
            "#[derive(Keys)] is for a section type without generics",
        ));
    }
    let Some(section) = section else {
        return Err(syn::Error::new_spanned(
            &input.ident,
            "#[derive(Keys)] needs #[keys(section = \"…\")]: the section's key path",
        ));
    };
    // Struct fields, or the named fields of every variant of an enum.
    let mut field_lists: Vec<&syn::FieldsNamed> = Vec::new();
    match &input.data {
        Data::Struct(s) => match &s.fields {
            Fields::Named(n) => field_lists.push(n),
            _ => {
                return Err(syn::Error::new_spanned(
                    &input.ident,
                    "#[derive(Keys)] needs named fields",
                ))
            }
        },
        Data::Enum(e) => {
            if want_default {
                return Err(syn::Error::new_spanned(
                    &input.ident,
                    "#[keys(default)] is for structs; an enum states its #[default] variant",
                ));
            }
            for v in &e.variants {
                if let Fields::Named(n) = &v.fields {
                    field_lists.push(n);
                }
            }
        }
        Data::Union(_) => {
            return Err(syn::Error::new_spanned(&input.ident, "unions have no keys"));
        }
    }

    let mut ranges: Vec<Range> = Vec::new();
    let mut defaults = Vec::new();
    for field in field_lists.iter().flat_map(|n| n.named.iter()) {
        let ident = field.ident.clone().expect("named field");
        let field_name = ident.unraw().to_string();
        // The key path is the field's name: a serde rename would make it another key.
        for attr in field.attrs.iter().filter(|a| a.path().is_ident("serde")) {
            let mut renamed = false;
            attr.parse_nested_meta(|meta| {
                renamed |= meta.path.is_ident("rename") || meta.path.is_ident("alias");
                if meta.input.peek(syn::Token![=]) {
                    meta.value()?.parse::<Expr>()?;
                } else if meta.input.peek(syn::token::Paren) {
                    meta.parse_nested_meta(|inner| {
                        if inner.input.peek(syn::Token![=]) {
                            inner.value()?.parse::<Expr>()?;
                        }
                        Ok(())
                    })?;
                }
                Ok(())
            })?;
            if renamed {
                return Err(syn::Error::new_spanned(
                    attr,
                    "a key's name is its field's: #[derive(Keys)] takes no serde rename or alias",
                ));
            }
        }
        let mut default: Option<Expr> = None;
        for attr in field.attrs.iter().filter(|a| a.path().is_ident("key")) {
            let mut range: Option<Expr> = None;
            let mut at = String::new();
            let mut name: Option<Ident> = None;
            attr.parse_nested_meta(|meta| {
                let twice = || meta.error("given twice in one #[key(…)]");
                if meta.path.is_ident("default") {
                    if default.is_some() {
                        return Err(meta.error("a key has one default"));
                    }
                    default = Some(meta.value()?.parse()?);
                } else if meta.path.is_ident("range") {
                    if range.is_some() {
                        return Err(twice());
                    }
                    range = Some(meta.value()?.parse()?);
                } else if meta.path.is_ident("at") {
                    at = meta.value()?.parse::<LitStr>()?.value();
                    let parts_ok = at.starts_with('[')
                        && at.ends_with(']')
                        && at
                            .chars()
                            .all(|c| c.is_ascii_digit() || c == '[' || c == ']');
                    if !parts_ok {
                        return Err(meta.error(
                            "`at` is a part of the value: `[]` (each element), `[0]` (one \
                             position), or several, e.g. `[][1]`",
                        ));
                    }
                } else if meta.path.is_ident("name") {
                    name = Some(meta.value()?.parse()?);
                } else {
                    return Err(meta.error(
                        "expected `default = …`, `range = …`, `at = \"[]…\"` or `name = …`",
                    ));
                }
                Ok(())
            })?;
            match range {
                Some(bound) => {
                    let name = match (name, at.is_empty()) {
                        (Some(n), _) => n,
                        (None, true) => format_ident!("{}", field_name.to_uppercase()),
                        (None, false) => {
                            return Err(syn::Error::new_spanned(
                                attr,
                                "a range `at` a part of the value needs `name = …`",
                            ))
                        }
                    };
                    ranges.push(Range {
                        name,
                        key: format!("{section}.{field_name}{at}"),
                        bound,
                    });
                }
                None if !at.is_empty() || name.is_some() => {
                    return Err(syn::Error::new_spanned(
                        attr,
                        "`at` and `name` belong to a `range`",
                    ));
                }
                None => {}
            }
        }
        if default.is_some() && !want_default {
            return Err(syn::Error::new_spanned(
                &ident,
                "a `default` here would be unused: the section states #[keys(default)] to \
                 have its Default written from its keys (else its own impl Default holds them)",
            ));
        }
        defaults.push(match default {
            Some(d) => quote! { #ident: #d },
            None => quote! { #ident: ::core::default::Default::default() },
        });
    }

    let ty = &input.ident;
    let consts = ranges.iter().map(|r| {
        let (name, key, bound) = (&r.name, &r.key, &r.bound);
        let doc = format!("The range of `{key}`.");
        quote! {
            #[doc = #doc]
            pub const #name: crate::config::bounds::Bound = (#bound).at(#key);
        }
    });
    let names = ranges.iter().map(|r| &r.name);
    let section_doc = format!("Every range of `{section}`.");
    let default_impl = want_default.then(|| {
        quote! {
            impl ::core::default::Default for #ty {
                fn default() -> Self {
                    Self { #(#defaults,)* }
                }
            }
        }
    });
    Ok(quote! {
        impl #ty {
            #(#consts)*
            #[doc = #section_doc]
            pub const BOUNDS: &'static [crate::config::bounds::Bound] = &[#(Self::#names),*];
        }
        #default_impl
    })
}
