//! A hint for CSV files written with another delimiter than the comma
//! (spreadsheets in locales with a decimal comma write `;`), shared by
//! every CSV reader of the workspace.

/// When a CSV header read with commas came out as one field holding `;`
/// or a tab, the sentence that says so; `None` otherwise.
///
/// ```
/// assert!(nlvid_study::delimiter_hint(&["time [s];force [N]"]).unwrap().contains("`;`"));
/// assert_eq!(nlvid_study::delimiter_hint(&["time [s]", "force [N]"]), None);
/// ```
pub fn delimiter_hint<S: AsRef<str>>(header: &[S]) -> Option<String> {
    let [only] = header else { return None };
    let only = only.as_ref();
    let (sep, name) = if only.contains(';') {
        (";", "`;`")
    } else if only.contains('\t') {
        ("\t", "a tab")
    } else {
        return None;
    };
    Some(format!(
        "the header is one field: the delimiter is {name} ({} parts), but nlvid reads \
         comma-separated files with `.` as the decimal mark; save the file as CSV with commas",
        only.split(sep).count()
    ))
}
