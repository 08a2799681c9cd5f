//! Collects debug-utils messages (validation layer, loader) so tests can fail
//! on any of them. The same sink receives messages during instance creation
//! and destruction through a messenger chained into `VkInstanceCreateInfo`.

use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::Mutex;

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Severity {
    Warning,
    Error,
}

#[derive(Debug, Clone)]
pub struct ValidationMessage {
    pub severity: Severity,
    /// `pMessageIdName`, e.g. "VUID-vkCmdDraw-None-08600"; the allowlist key.
    pub id_name: String,
    pub text: String,
}

/// Every warning and error any messenger of one context reported.
#[derive(Debug, Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<ValidationMessage>>,
}

impl ValidationLog {
    pub fn messages(&self) -> Vec<ValidationMessage> {
        self.messages.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Messages whose id is not in `allow` ((id, reason) pairs).
    pub fn unexpected(&self, allow: &[(&str, &str)]) -> Vec<ValidationMessage> {
        self.messages().into_iter().filter(|m| !allow.iter().any(|(id, _)| *id == m.id_name)).collect()
    }

    pub fn clear(&self) {
        self.messages.lock().unwrap_or_else(|e| e.into_inner()).clear();
    }

    fn push(&self, m: ValidationMessage) {
        self.messages.lock().unwrap_or_else(|e| e.into_inner()).push(m);
    }
}

fn cstr_lossy(p: *const std::ffi::c_char) -> String {
    if p.is_null() {
        return String::new();
    }
    // SAFETY: the layer passes NUL-terminated strings valid for the callback.
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

/// `user_data` is a `*const ValidationLog` kept alive by the context until
/// after the instance is destroyed.
pub(crate) unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user_data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: the pointers come from the layer (data) and from us (user_data,
    // a live ValidationLog); both are valid for the duration of the call.
    let (data, log) = unsafe { (&*data, &*(user_data as *const ValidationLog)) };
    let msg = ValidationMessage {
        severity: if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            Severity::Error
        } else {
            Severity::Warning
        },
        id_name: cstr_lossy(data.p_message_id_name),
        text: cstr_lossy(data.p_message),
    };
    log::warn!("vulkan {:?} [{}]: {}", msg.severity, msg.id_name, msg.text);
    log.push(msg);
    vk::FALSE
}

pub(crate) fn messenger_info(log: &ValidationLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(callback))
        .user_data(log as *const ValidationLog as *mut c_void)
}
