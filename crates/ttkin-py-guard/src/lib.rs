//! `#[guarded]`: the one panic guard of the ttmanip bindings.
//!
//! Put `#[guarded]` above a `#[pymethods]` impl block or a `#[pyfunction]`. Every function body
//! is moved into a closure run by `crate::guard::call(name, ..)` (in `ttkin-py`), which catches a
//! Rust panic with `std::panic::catch_unwind` and returns it as `ttmanip.InternalError` (a
//! `TtmanipError`) instead of PyO3's `PanicException`, which derives from `BaseException` and so
//! escapes `except Exception`. Functions that do not return a `PyResult` get `PyResult<T>` as
//! their return type (PyO3 accepts both). The guard costs one landing pad, no run-time work.
//!
//! It also names scalar arguments: every parameter typed `f64`, an integer type or an `Option`
//! of one gets `#[pyo3(from_py_with = ..)]` with a small generated extractor that calls
//! `crate::args::scalar(obj, "name")`, so a Python int out of range (`10**400` for a float, `-1`
//! for a count) raises a `TtmanipError` naming the argument and the accepted range rather than
//! PyO3's bare `OverflowError`. Defaults and text signatures are unchanged.

#![forbid(unsafe_code)]

use proc_macro::TokenStream;
use quote::quote;
use syn::{
    parse_macro_input, parse_quote, Attribute, Block, FnArg, ImplItem, Item, ItemFn, Pat, ReturnType, Signature, Type,
};

/// Wraps every function of a `#[pymethods]` block (or one `#[pyfunction]`) in the panic guard.
#[proc_macro_attribute]
pub fn guarded(attr: TokenStream, item: TokenStream) -> TokenStream {
    if !attr.is_empty() {
        return syn::Error::new(proc_macro2::Span::call_site(), "#[guarded] takes no arguments")
            .to_compile_error()
            .into();
    }
    let mut item = parse_macro_input!(item as Item);
    let mut extractors: Vec<ItemFn> = Vec::new();
    match &mut item {
        Item::Fn(f) => {
            let name = f.sig.ident.to_string();
            name_scalars(&name, &f.attrs, &mut f.sig, &mut extractors);
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
                    name_scalars(&name, &m.attrs, &mut m.sig, &mut extractors);
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
    quote!(#item #(#extractors)*).into()
}

/// The scalar types whose extraction `crate::args::scalar` takes over (spelled without spaces).
const SCALARS: &[&str] = &["f64", "i128", "i64", "i32", "u64", "u32", "u16", "u8", "usize"];

/// Whether `ty` is one of [`SCALARS`] or an `Option` of one.
fn is_scalar(ty: &Type) -> bool {
    let spelled = quote!(#ty).to_string().replace(' ', "");
    let inner = spelled
        .strip_prefix("Option<")
        .and_then(|s| s.strip_suffix('>'))
        .unwrap_or(&spelled);
    SCALARS.contains(&inner)
}

/// Puts `#[pyo3(from_py_with = ..)]` on every scalar parameter of the function `name` (which has
/// attributes `attrs`), with its extractor pushed onto `out` (a function beside the item).
fn name_scalars(name: &str, attrs: &[Attribute], sig: &mut Signature, out: &mut Vec<ItemFn>) {
    let setter = attrs.iter().any(|a| a.path().is_ident("setter"));
    for input in &mut sig.inputs {
        let FnArg::Typed(arg) = input else { continue };
        if !is_scalar(&arg.ty) || arg.attrs.iter().any(|a| a.path().is_ident("pyo3")) {
            continue;
        }
        let Pat::Ident(ident) = &*arg.pat else { continue };
        let param = ident.ident.to_string();
        let param = param.strip_prefix("r#").unwrap_or(&param).to_string();
        // a setter's value is named after its property (`set_gain` sets `gain`)
        let shown = if setter {
            sig.ident.to_string().strip_prefix("set_").unwrap_or(&param).to_string()
        } else {
            param.clone()
        };
        let fn_name = syn::Ident::new(
            &format!("__ttkin_arg_{}_{}", name.replace('.', "_"), param),
            proc_macro2::Span::call_site(),
        );
        let ty = &arg.ty;
        out.push(parse_quote! {
            #[doc(hidden)]
            #[allow(non_snake_case)]
            fn #fn_name(obj: &::pyo3::Bound<'_, ::pyo3::PyAny>) -> ::pyo3::PyResult<#ty> {
                crate::args::scalar::<#ty>(obj, #shown)
            }
        });
        arg.attrs.push(parse_quote!(#[pyo3(from_py_with = #fn_name)]));
    }
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
