//! The bowed-string voice: the McIntyre–Schumacher–Woodhouse rounded-corner model and the STK
//! bow-table tier (`shared/notes/bowed-model.md`).
