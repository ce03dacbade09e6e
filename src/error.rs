//! The library's error type: what went wrong, named so a user can act on it.

use std::path::PathBuf;

use crate::imageio::ImageIoError;
use crate::material::MaterialError;
use crate::shader::ShaderError;
use crate::variant::VariantError;
use crate::vk::VkError;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Vk(#[from] VkError),
    #[error(transparent)]
    Shader(#[from] ShaderError),
    #[error(transparent)]
    Variant(#[from] VariantError),
    #[error(transparent)]
    Material(#[from] MaterialError),
    #[error(transparent)]
    ImageIo(#[from] ImageIoError),
    #[error("{path}: {message}")]
    Input { path: PathBuf, message: String },
    #[error("writing {path}: {message}")]
    Output { path: PathBuf, message: String },
    #[error("{0}")]
    Unsupported(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;
