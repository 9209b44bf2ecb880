//! Multibody problems built in code.
