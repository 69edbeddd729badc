//! `#[guarded]`: the one panic guard of the ttmanip bindings.
//!
//! Put `#[guarded]` above a `#[pymethods]` impl block or a `#[pyfunction]`. Every function body
//! is moved into a closure run by `crate::guard::call(name, ..)` (in `ttkin-py`), which catches a
//! Rust panic with `std::panic::catch_unwind` and returns it as `ttmanip.InternalError` (a
//! `TtmanipError`) instead of PyO3's `PanicException`, which derives from `BaseException` and so
//! escapes `except Exception`. Functions that do not return a `PyResult` get `PyResult<T>` as
//! their return type (PyO3 accepts both). The guard costs one landing pad, no run-time work.

#![forbid(unsafe_code)]

use proc_macro::TokenStream;
use quote::quote;
use syn::{parse_macro_input, parse_quote, Block, ImplItem, Item, ReturnType, Signature, Type};

/// Wraps every function of a `#[pymethods]` block (or one `#[pyfunction]`) in the panic guard.
#[proc_macro_attribute]
pub fn guarded(attr: TokenStream, item: TokenStream) -> TokenStream {
    if !attr.is_empty() {
        return syn::Error::new(proc_macro2::Span::call_site(), "#[guarded] takes no arguments")
            .to_compile_error()
            .into();
    }
    let mut item = parse_macro_input!(item as Item);
    match &mut item {
        Item::Fn(f) => {
            let name = f.sig.ident.to_string();
            wrap(&name, &mut f.sig, &mut f.block);
        }
        Item::Impl(imp) => {
            let owner = python_name(&imp.self_ty);
            for it in &mut imp.items {
                if let ImplItem::Fn(m) = it {
                    // PyO3's GC hooks have fixed signatures and must not call into Python.
                    if matches!(m.sig.ident.to_string().as_str(), "__traverse__" | "__clear__") {
                        continue;
                    }
                    let name = format!("{owner}.{}", m.sig.ident);
                    wrap(&name, &mut m.sig, &mut m.block);
                }
            }
        }
        other => {
            return syn::Error::new_spanned(other, "#[guarded] goes on a #[pymethods] impl block or a #[pyfunction]")
                .to_compile_error()
                .into();
        }
    }
    quote!(#item).into()
}

/// `PyRobot` → `Robot`: the class name Python users see, for error messages.
fn python_name(ty: &Type) -> String {
    let raw = match ty {
        Type::Path(p) => p.path.segments.last().map(|s| s.ident.to_string()).unwrap_or_default(),
        _ => String::from("?"),
    };
    raw.strip_prefix("Py").map(str::to_string).unwrap_or(raw)
}

/// True when the return type is spelled `PyResult<..>` (or `...::PyResult<..>`).
fn returns_pyresult(sig: &Signature) -> bool {
    match &sig.output {
        ReturnType::Type(_, ty) => match &**ty {
            Type::Path(p) => p.path.segments.last().is_some_and(|s| s.ident == "PyResult"),
            _ => false,
        },
        ReturnType::Default => false,
    }
}

fn wrap(name: &str, sig: &mut Signature, block: &mut Block) {
    let body = block.clone();
    if returns_pyresult(sig) {
        *block = parse_quote!({ crate::guard::call(#name, move || #body) });
    } else {
        let ty: Type = match &sig.output {
            ReturnType::Type(_, ty) => (**ty).clone(),
            ReturnType::Default => parse_quote!(()),
        };
        sig.output = parse_quote!(-> ::pyo3::PyResult<#ty>);
        *block = parse_quote!({
            crate::guard::call(#name, move || ::std::result::Result::Ok((move || #body)()))
        });
    }
}
