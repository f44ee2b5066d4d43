//! The app-backed objects: each generated hook hands its read or write to the [`Logger`],
//! which owns the card, the clock and the files. The dictionary has checked access, length
//! and limits before a hook runs; the hooks check what depends on the configuration (a
//! component's type, an 8.3 name, a record address inside the file).

use crate::app::Hooks;
use crate::card::files::FILES;
use crate::card::record::COMPONENTS;
use crate::card::record::ComponentType;
use crate::clock::Field;
use crate::logger::Logger;
use crate::logger::file_config::{Component, RING, Text};
use coforge_stack::od::{ReadLen, SdoAbort, WriteSource, read_slice};
use embedded_sdmmc::BlockDevice;

fn u8_of(data: &[u8]) -> Result<u8, SdoAbort> {
    data.first().copied().ok_or(SdoAbort::LengthTooLow)
}

fn u16_of(data: &[u8]) -> Result<u16, SdoAbort> {
    Ok(u16::from_le_bytes(data.try_into().map_err(|_| SdoAbort::LengthMismatch)?))
}

fn u32_of(data: &[u8]) -> Result<u32, SdoAbort> {
    Ok(u32::from_le_bytes(data.try_into().map_err(|_| SdoAbort::LengthMismatch)?))
}

/// A file's number (0-based) from a hook's object number.
fn file(n: u16) -> Result<usize, SdoAbort> {
    Some(usize::from(n)).filter(|&n| n < FILES).ok_or(SdoAbort::NoObject)
}

/// A time stamp field (2010h, 5x00h subs 1..7) as its bytes.
fn field_bytes(field: Field, t: &crate::card::record::TimeStamp) -> ([u8; 2], usize) {
    let (value, size) = field.get(t);
    (value.to_le_bytes(), size)
}

fn read_field(field: Field, t: &crate::card::record::TimeStamp, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
    let (bytes, size) = field_bytes(field, t);
    read_slice(bytes.get(..size).unwrap_or_default(), offset, buf)
}

impl<D: BlockDevice> Hooks for Logger<D> {
    /// The device reads the RPDOs' identifiers again after a write to their parameters,
    /// rather than at every frame.
    fn written(&mut self, index: u16, _sub: u8, _data: &[u8], _by: WriteSource) {
        if (0x1400..0x1400 + FILES as u16).contains(&index) {
            self.rpdo_parameters_written = true;
        }
    }

    fn read_name_of_the_memory_card(&mut self, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        self.require_card()?;
        read_slice(self.settings().name.as_bytes(), offset, buf)
    }

    fn write_name_of_the_memory_card(&mut self, data: &[u8]) -> Result<(), SdoAbort> {
        self.set_card_name(data)
    }

    fn read_memory_allocation(&mut self, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        match sub {
            0 => read_slice(&[FILES as u8], offset, buf),
            _ => read_slice(&self.allocation(usize::from(sub) - 1, false)?.to_le_bytes(), offset, buf),
        }
    }

    fn write_memory_allocation(&mut self, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.set_allocation(usize::from(sub).wrapping_sub(1), false, u32_of(data)?)
    }

    fn read_memory_allocation_shadow(&mut self, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        match sub {
            0 => read_slice(&[FILES as u8], offset, buf),
            _ => read_slice(&self.allocation(usize::from(sub) - 1, true)?.to_le_bytes(), offset, buf),
        }
    }

    fn write_memory_allocation_shadow(&mut self, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.set_allocation(usize::from(sub).wrapping_sub(1), true, u32_of(data)?)
    }

    fn read_date_time(&mut self, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        match Field::of_sub(sub) {
            Some(field) => read_field(field, &self.now(), offset, buf),
            None => read_slice(&[7], offset, buf),
        }
    }

    fn write_date_time(&mut self, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        let field = Field::of_sub(sub).ok_or(SdoAbort::ReadOnly)?;
        let value = if field == Field::Millisecond { u16_of(data)? } else { u16::from(u8_of(data)?) };
        let now = self.now_us();
        self.clock_mut().set(field, value, now)
    }

    fn read_designation_file(&mut self, n: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        self.require_card()?;
        let f = self.file(file(n)?)?;
        match sub {
            0 => read_slice(&[2], offset, buf),
            1 => read_slice(f.name(), offset, buf),
            _ => read_slice(f.extension(), offset, buf),
        }
    }

    fn write_designation_file(&mut self, n: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.configure_file(file(n)?, |f, _| if sub == 1 { f.set_name(data) } else { f.set_extension(data) })
    }

    fn read_relevant_components_in_file(&mut self, n: u16) -> Result<u16, SdoAbort> {
        self.require_card()?;
        Ok(self.file(file(n)?)?.relevant)
    }

    fn write_relevant_components_in_file(&mut self, n: u16, value: u16) -> Result<(), SdoAbort> {
        self.configure_file(file(n)?, |f, _| {
            f.relevant = value;
            Ok(())
        })
    }

    fn read_configuration_file(&mut self, n: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        self.require_card()?;
        let f = self.file(file(n)?)?;
        match sub {
            0 => read_slice(&[3], offset, buf),
            1 => read_slice(&[f.mode().code()], offset, buf),
            2 => read_slice(&[if f.ring { RING } else { 0 }], offset, buf),
            _ => read_slice(&f.interval().to_le_bytes(), offset, buf),
        }
    }

    fn write_configuration_file(&mut self, n: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.configure_file(file(n)?, |f, _| match sub {
            1 => f.set_mode(u8_of(data)?),
            2 => {
                f.ring = u8_of(data)? == RING;
                Ok(())
            }
            _ => f.set_interval(u32_of(data)?),
        })
    }

    fn read_current_data_record_file(&mut self, n: u16) -> Result<u32, SdoAbort> {
        self.require_card()?;
        Ok(self.file(file(n)?)?.current())
    }

    fn write_current_data_record_file(&mut self, n: u16, value: u32) -> Result<(), SdoAbort> {
        self.set_current(file(n)?, value)
    }

    fn read_current_data_record_file_write_pointer(&mut self, n: u16) -> Result<u32, SdoAbort> {
        self.require_card()?;
        Ok(self.file(file(n)?)?.write_pointer())
    }

    fn write_current_data_record_file_write_pointer(&mut self, n: u16, value: u32) -> Result<(), SdoAbort> {
        self.configure_file(file(n)?, |f, size| f.set_write_pointer(value, size))
    }

    fn read_number_of_data_records_file(&mut self, n: u16) -> Result<u32, SdoAbort> {
        self.require_card()?;
        Ok(self.file(file(n)?)?.count())
    }

    fn write_number_of_data_records_file(&mut self, n: u16, value: u32) -> Result<(), SdoAbort> {
        self.configure_file(file(n)?, |f, _| f.reset_count(value))
    }

    fn read_component_file_1(&mut self, n: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        self.require_card()?;
        let (f, c) = (usize::from(n) / COMPONENTS, usize::from(n) % COMPONENTS);
        let component = *self.file(file(f as u16)?)?.components.get(c).ok_or(SdoAbort::NoObject)?;
        match sub {
            0 => read_slice(&[2], offset, buf),
            1 => read_slice(component.name.as_bytes(), offset, buf),
            _ => read_slice(&component.ty.code().to_le_bytes(), offset, buf),
        }
    }

    fn write_component_file_1(&mut self, n: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        let (f, c) = (usize::from(n) / COMPONENTS, usize::from(n) % COMPONENTS);
        self.configure_file(file(f as u16)?, |file, _| {
            let component: &mut Component = file.components.get_mut(c).ok_or(SdoAbort::NoObject)?;
            if sub == 1 {
                component.name = Text::new(data).ok_or(SdoAbort::LengthTooHigh)?;
            } else {
                // The dictionary's limits are 0003h..0008h: every code in them is a type.
                component.ty = ComponentType::of_code(u16_of(data)?).ok_or(SdoAbort::InvalidValue)?;
            }
            Ok(())
        })
    }

    fn read_data_of_the_components_1_8_file(&mut self, n: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        let f = file(n)?;
        if sub == 0 {
            return read_slice(&[15], offset, buf);
        }
        let record = self.shown(f)?;
        if let Some(field) = Field::of_sub(sub) {
            return read_field(field, &record.time_stamp(), offset, buf);
        }
        let c = usize::from(sub) - 8;
        let layout = self.file(f)?.layout();
        match record.get(&layout, c) {
            Some(value) => read_slice(value, offset, buf),
            // Not relevant: zeros at the component's size (erratum CR-26).
            None => read_slice([0; 4].get(..layout.types.get(c).map_or(2, |t| t.size())).unwrap_or_default(), offset, buf),
        }
    }

    fn write_data_of_the_components_1_8_file(&mut self, n: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        let f = file(n)?;
        let c = usize::from(sub).checked_sub(8).ok_or(SdoAbort::ReadOnly)?;
        self.write_component(f, c, data)?;
        self.end_input(f);
        Ok(())
    }
}
