//! `Clone` for the dictionary's types. `clone_from` reuses the buffers of
//! the copy it overwrites: a dictionary reset to a template
//! (`ObjectDictionary::clone_from`, e.g. a fuzz target's node per input)
//! then allocates nothing where the structure is the same. The
//! destructuring makes a new field a compile error here.

use super::{Object, ObjectDictionary, SubObject};

impl Clone for SubObject {
    fn clone(&self) -> Self {
        let SubObject {
            sub,
            name,
            data_type,
            access,
            pdo_mappable,
            low_limit,
            high_limit,
            default,
            persist,
            max_len,
            owner,
            live,
            watched,
            marked,
            node_id_relative,
            value,
        } = self;
        SubObject {
            sub: *sub,
            name: name.clone(),
            data_type: *data_type,
            access: *access,
            pdo_mappable: *pdo_mappable,
            low_limit: low_limit.clone(),
            high_limit: high_limit.clone(),
            default: default.clone(),
            persist: *persist,
            max_len: *max_len,
            owner: *owner,
            live: *live,
            watched: *watched,
            marked: *marked,
            node_id_relative: *node_id_relative,
            value: value.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        let SubObject {
            sub,
            name,
            data_type,
            access,
            pdo_mappable,
            low_limit,
            high_limit,
            default,
            persist,
            max_len,
            owner,
            live,
            watched,
            marked,
            node_id_relative,
            value,
        } = source;
        self.sub = *sub;
        self.name.clone_from(name);
        self.data_type = *data_type;
        self.access = *access;
        self.pdo_mappable = *pdo_mappable;
        self.low_limit.clone_from(low_limit);
        self.high_limit.clone_from(high_limit);
        self.default.clone_from(default);
        self.persist = *persist;
        self.max_len = *max_len;
        self.owner = *owner;
        self.live = *live;
        self.watched = *watched;
        self.marked = *marked;
        self.node_id_relative = *node_id_relative;
        self.value.clone_from(value);
    }
}

impl Clone for Object {
    fn clone(&self) -> Self {
        let Object { index, code, name, flags, subs } = self;
        Object { index: *index, code: *code, name: name.clone(), flags: *flags, subs: subs.clone() }
    }

    fn clone_from(&mut self, source: &Self) {
        let Object { index, code, name, flags, subs } = source;
        self.index = *index;
        self.code = *code;
        self.name.clone_from(name);
        self.flags = *flags;
        self.subs.clone_from(subs);
    }
}

impl Clone for ObjectDictionary {
    fn clone(&self) -> Self {
        let ObjectDictionary { objects, keys, generation } = self;
        ObjectDictionary { objects: objects.clone(), keys: keys.clone(), generation: *generation }
    }

    fn clone_from(&mut self, source: &Self) {
        let ObjectDictionary { objects, keys, generation } = source;
        self.objects.clone_from(objects);
        self.keys.clone_from(keys);
        self.generation = *generation;
    }
}
