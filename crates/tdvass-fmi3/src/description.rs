//! The FMI 3.0 `modelDescription.xml` and `documentation/index.html`,
//! generated from the one variable table (quick-xml, never written by hand).
