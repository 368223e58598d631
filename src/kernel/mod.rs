//! The KERNEL protocol personality (ICD section 5, Appendix A).

pub mod frame;
